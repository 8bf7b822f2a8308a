// Instance, device choice and validation-error counting.
#include "compute.h"

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace uvpress::engine::vk {

void check(VkResult result, const char* what) {
  if (result != VK_SUCCESS)
    throw EngineError(std::string("Vulkan: ") + what + " failed (VkResult " + std::to_string(int(result)) + ")");
}

namespace {

bool has_layer(const char* name) {
  uint32_t n = 0;
  vkEnumerateInstanceLayerProperties(&n, nullptr);
  std::vector<VkLayerProperties> layers(n);
  vkEnumerateInstanceLayerProperties(&n, layers.data());
  for (auto& l : layers)
    if (std::strcmp(l.layerName, name) == 0) return true;
  return false;
}

bool has_instance_extension(const char* name) {
  uint32_t n = 0;
  vkEnumerateInstanceExtensionProperties(nullptr, &n, nullptr);
  std::vector<VkExtensionProperties> ext(n);
  vkEnumerateInstanceExtensionProperties(nullptr, &n, ext.data());
  for (auto& e : ext)
    if (std::strcmp(e.extensionName, name) == 0) return true;
  return false;
}

const char* type_name(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete-gpu";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated-gpu";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual-gpu";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "cpu";
    default: return "other";
  }
}

// Lower is better; -1: not eligible for the request.
int rank(DeviceRequest request, VkPhysicalDeviceType t) {
  if (request == DeviceRequest::Lavapipe) return t == VK_PHYSICAL_DEVICE_TYPE_CPU ? 0 : -1;
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    default: return -1;
  }
}

int compute_queue_family(VkPhysicalDevice physical) {
  uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(physical, &n, nullptr);
  std::vector<VkQueueFamilyProperties> families(n);
  vkGetPhysicalDeviceQueueFamilyProperties(physical, &n, families.data());
  // Prefer a compute-only family (async compute on GPUs), else any with compute.
  for (uint32_t i = 0; i < n; ++i)
    if ((families[i].queueFlags & VK_QUEUE_COMPUTE_BIT) && !(families[i].queueFlags & VK_QUEUE_GRAPHICS_BIT)) return int(i);
  for (uint32_t i = 0; i < n; ++i)
    if (families[i].queueFlags & VK_QUEUE_COMPUTE_BIT) return int(i);
  return -1;
}

}  // namespace

Context::Context(DeviceRequest request, bool validation) {
  auto app = make<VkApplicationInfo>(VK_STRUCTURE_TYPE_APPLICATION_INFO);
  app.pApplicationName = "uvpress";
  app.pEngineName = "uvpress";
  app.apiVersion = VK_API_VERSION_1_1;

  std::vector<const char*> layers, extensions;
  if (validation) {
    if (!has_layer("VK_LAYER_KHRONOS_validation"))
      throw EngineError("Vulkan validation requested but VK_LAYER_KHRONOS_validation is not installed (vulkan-validationlayers)");
    if (!has_instance_extension(VK_EXT_DEBUG_UTILS_EXTENSION_NAME))
      throw EngineError("Vulkan validation requested but VK_EXT_debug_utils is missing");
    layers.push_back("VK_LAYER_KHRONOS_validation");
    extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  }

  auto messenger_info = make<VkDebugUtilsMessengerCreateInfoEXT>(VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT);
  messenger_info.messageSeverity =
      VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  messenger_info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                               VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                               VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
  messenger_info.pfnUserCallback = &Context::on_message;
  messenger_info.pUserData = this;

  auto ici = make<VkInstanceCreateInfo>(VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO);
  ici.pApplicationInfo = &app;
  ici.enabledLayerCount = uint32_t(layers.size());
  ici.ppEnabledLayerNames = layers.data();
  ici.enabledExtensionCount = uint32_t(extensions.size());
  ici.ppEnabledExtensionNames = extensions.data();
  if (validation) ici.pNext = &messenger_info;  // also catches errors in create/destroy instance
  VkResult r = vkCreateInstance(&ici, nullptr, &instance_);
  if (r != VK_SUCCESS)
    throw EngineError("Vulkan is not available (vkCreateInstance: VkResult " + std::to_string(int(r)) +
                      "); install a driver, e.g. mesa-vulkan-drivers for lavapipe");

  try {
    if (validation) {
      auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
          vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
      check(create ? create(instance_, &messenger_info, nullptr, &messenger_) : VK_ERROR_EXTENSION_NOT_PRESENT,
            "vkCreateDebugUtilsMessengerEXT");
    }

    uint32_t n = 0;
    vkEnumeratePhysicalDevices(instance_, &n, nullptr);
    std::vector<VkPhysicalDevice> devices(n);
    vkEnumeratePhysicalDevices(instance_, &n, devices.data());
    int best = -1, best_family = -1;
    for (uint32_t i = 0; i < n; ++i) {
      VkPhysicalDeviceProperties p;
      vkGetPhysicalDeviceProperties(devices[i], &p);
      int rk = rank(request, p.deviceType), family = compute_queue_family(devices[i]);
      if (rk < 0 || family < 0 || p.apiVersion < VK_API_VERSION_1_1) continue;
      if (best < 0 || rk < rank(request, properties_.deviceType)) {
        best = int(i), best_family = family, properties_ = p;
      }
    }
    if (best < 0)
      throw EngineError(request == DeviceRequest::Lavapipe
                            ? "no CPU Vulkan device (lavapipe) found; install mesa-vulkan-drivers"
                            : "no Vulkan GPU found; use --device cpu or --device lavapipe");
    physical_ = devices[size_t(best)];
    queue_family_ = uint32_t(best_family);
    vkGetPhysicalDeviceMemoryProperties(physical_, &memory_);

    auto m3 = make<VkPhysicalDeviceMaintenance3Properties>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES);
    auto p2 = make<VkPhysicalDeviceProperties2>(VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2);
    p2.pNext = &m3;
    vkGetPhysicalDeviceProperties2(physical_, &p2);
    max_buffer_bytes_ = std::min<uint64_t>(properties_.limits.maxStorageBufferRange, m3.maxMemoryAllocationSize);

    float priority = 1.0f;
    auto qci = make<VkDeviceQueueCreateInfo>(VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO);
    qci.queueFamilyIndex = queue_family_;
    qci.queueCount = 1;
    qci.pQueuePriorities = &priority;
    auto dci = make<VkDeviceCreateInfo>(VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO);
    dci.queueCreateInfoCount = 1;
    dci.pQueueCreateInfos = &qci;
    check(vkCreateDevice(physical_, &dci, nullptr, &device_), "vkCreateDevice");
    vkGetDeviceQueue(device_, queue_family_, 0, &queue_);

    info_.backend = "vulkan";
    info_.name = properties_.deviceName;
    info_.type = type_name(properties_.deviceType);
    info_.threads = 1;
  } catch (...) {
    release();
    throw;
  }
}

Context::~Context() { release(); }

void Context::release() {
  if (device_) vkDestroyDevice(device_, nullptr);
  device_ = VK_NULL_HANDLE;
  if (messenger_) {
    auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroy) destroy(instance_, messenger_, nullptr);
    messenger_ = VK_NULL_HANDLE;
  }
  if (instance_) vkDestroyInstance(instance_, nullptr);
  instance_ = VK_NULL_HANDLE;
}

uint32_t Context::memory_type(uint32_t type_bits, VkMemoryPropertyFlags required,
                              VkMemoryPropertyFlags preferred) const {
  int best = -1, best_rank = 3;
  for (uint32_t i = 0; i < memory_.memoryTypeCount; ++i) {
    if (!(type_bits & (1u << i))) continue;
    VkMemoryPropertyFlags f = memory_.memoryTypes[i].propertyFlags;
    if ((f & required) != required) continue;
    const int rank = (f & preferred) == preferred ? 0 : (f & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT) ? 1 : 2;
    if (rank < best_rank) best = int(i), best_rank = rank;
  }
  if (best < 0) throw EngineError("Vulkan: no host-visible memory type for a storage buffer");
  return uint32_t(best);
}

VKAPI_ATTR VkBool32 VKAPI_CALL Context::on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                   VkDebugUtilsMessageTypeFlagsEXT,
                                                   const VkDebugUtilsMessengerCallbackDataEXT* data, void* self) {
  bool error = severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  if (error) static_cast<Context*>(self)->validation_errors_++;
  std::fprintf(stderr, "vulkan %s: %s\n", error ? "error" : "warning", data && data->pMessage ? data->pMessage : "");
  return VK_FALSE;
}

}  // namespace uvpress::engine::vk
