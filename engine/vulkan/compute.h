// The Vulkan vocabulary of the engine, after Kompute: a Context (instance, one device, one
// compute queue), Buffers (host-visible storage), Kernels (a compute pipeline from embedded
// SPIR-V) and Sequences (many dispatches recorded into one command buffer, one fence).
#pragma once

#include "engine.h"

#include <vulkan/vulkan.h>

#include <atomic>
#include <cstdint>
#include <initializer_list>
#include <memory>

namespace uvpress::engine::vk {

// A zero-initialized Vulkan info struct with its sType set.
template <class T>
T make(VkStructureType type) {
  T value{};
  value.sType = type;
  return value;
}

// Throws EngineError naming the call when `result` is not VK_SUCCESS.
void check(VkResult result, const char* what);

class Context {
 public:
  // Picks the device for `request` (Gpu: discrete > integrated > virtual; Lavapipe: a CPU
  // device). Throws EngineError when Vulkan or such a device is missing.
  Context(DeviceRequest request, bool validation);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  VkDevice device() const { return device_; }
  VkQueue queue() const { return queue_; }
  uint32_t queue_family() const { return queue_family_; }
  const VkPhysicalDeviceLimits& limits() const { return properties_.limits; }
  const DeviceInfo& info() const { return info_; }
  // The largest storage buffer this device takes (lavapipe: 128 MiB).
  uint64_t max_buffer_bytes() const { return max_buffer_bytes_; }
  uint64_t validation_errors() const { return validation_errors_.load(); }

  // A memory type with all of `required` among `type_bits`: one that also has all of
  // `preferred` if there is one, else one with DEVICE_LOCAL (resizable BAR, unified memory,
  // lavapipe), else the first.
  uint32_t memory_type(uint32_t type_bits, VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred) const;

 private:
  void release();
  static VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                   VkDebugUtilsMessageTypeFlagsEXT types,
                                                   const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                   void* self);

  VkInstance instance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkPhysicalDeviceProperties properties_{};
  VkPhysicalDeviceMemoryProperties memory_{};
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  uint32_t queue_family_ = 0;
  uint64_t max_buffer_bytes_ = 0;
  DeviceInfo info_;
  std::atomic<uint64_t> validation_errors_{0};
};

// What the host does with a buffer's contents, which decides the memory it lives in. On a
// discrete GPU with resizable BAR the device-local, host-visible memory takes the host's writes
// at bus speed, but the host reads it uncached, across the bus, at tens of MB/s: on an H200,
// eval's 20 views of Duck (1248^2 luminance floats and coverage, 250 MB) took 11.9 s to read
// back. A buffer the host reads lives in host-cached memory instead, which the device writes
// across the bus once. On
// lavapipe and unified-memory GPUs one memory type has every property, so both are the same.
enum class HostAccess {
  Write,  // the host writes it (inputs) or never touches it (scratch): device-local
  Read,   // the host reads the device's results from it: host-cached
};

// A host-visible, coherent storage buffer, persistently mapped.
class Buffer {
 public:
  Buffer(Context& context, uint64_t bytes, HostAccess access = HostAccess::Write);
  ~Buffer();
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;

  VkBuffer handle() const { return buffer_; }
  uint64_t bytes() const { return bytes_; }
  template <class T> T* data() { return static_cast<T*>(mapped_); }

 private:
  Context& context_;
  VkBuffer buffer_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  void* mapped_ = nullptr;
  uint64_t bytes_ = 0;
};

// The buffer in `slot`, replaced by a bigger one only when a call needs more than it holds:
// buffers live across batches and rounds.
Buffer& reuse(Context& context, std::unique_ptr<Buffer>& slot, uint64_t bytes, HostAccess access = HostAccess::Write);

// A compute pipeline: `buffers` storage buffers at bindings 0..n-1, `push_bytes` of push
// constants, the 2-D workgroup size as specialization constants 0 and 1.
class Kernel {
 public:
  Kernel(Context& context, const uint32_t* spirv, size_t spirv_bytes, uint32_t buffers,
         uint32_t push_bytes, uint32_t local_x, uint32_t local_y);
  ~Kernel();
  Kernel(const Kernel&) = delete;
  Kernel& operator=(const Kernel&) = delete;

  uint32_t local_x() const { return local_x_; }
  uint32_t local_y() const { return local_y_; }

 private:
  friend class Sequence;
  void release();
  Context& context_;
  VkShaderModule module_ = VK_NULL_HANDLE;
  VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
  uint32_t buffers_, push_bytes_, local_x_, local_y_;
};

// Records many dispatches into one command buffer and submits them with one fence.
class Sequence {
 public:
  explicit Sequence(Context& context, uint32_t max_dispatches = 1024);
  ~Sequence();
  Sequence(const Sequence&) = delete;
  Sequence& operator=(const Sequence&) = delete;

  void begin();
  void dispatch(const Kernel& kernel, std::initializer_list<const Buffer*> buffers, const void* push,
                uint32_t groups_x, uint32_t groups_y, uint32_t groups_z);
  // Makes every shader write so far visible to the dispatches recorded after it.
  void barrier();
  // Ends the command buffer (making shader writes visible to the host), submits and waits.
  void submit_and_wait();

 private:
  void release();
  Context& context_;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  VkCommandBuffer commands_ = VK_NULL_HANDLE;
  VkDescriptorPool descriptors_ = VK_NULL_HANDLE;
  VkFence fence_ = VK_NULL_HANDLE;
  uint32_t max_dispatches_, dispatches_ = 0;
};

}  // namespace uvpress::engine::vk
