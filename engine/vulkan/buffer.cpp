// Host-visible storage buffers, in the memory their HostAccess asks for (compute.h). On
// lavapipe and unified-memory GPUs every type is device-local, host-visible and cached, so
// there is no staging copy to make; on a discrete GPU the device reads inputs from its own
// memory and writes results into the host's.
#include "compute.h"

#include <string>

namespace uvpress::engine::vk {

Buffer::Buffer(Context& context, uint64_t bytes, HostAccess access) : context_(context), bytes_(bytes) {
  if (bytes == 0 || bytes > context.max_buffer_bytes())
    throw EngineError("Vulkan: buffer of " + std::to_string(bytes) + " bytes is outside the device's limit of " +
                      std::to_string(context.max_buffer_bytes()));
  auto bci = make<VkBufferCreateInfo>(VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO);
  bci.size = bytes;
  bci.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  check(vkCreateBuffer(context.device(), &bci, nullptr, &buffer_), "vkCreateBuffer");
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(context.device(), buffer_, &req);
  auto mai = make<VkMemoryAllocateInfo>(VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO);
  mai.allocationSize = req.size;
  try {
    mai.memoryTypeIndex = context.memory_type(
        req.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
        access == HostAccess::Read ? VK_MEMORY_PROPERTY_HOST_CACHED_BIT : VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    check(vkAllocateMemory(context.device(), &mai, nullptr, &memory_), "vkAllocateMemory");
    check(vkBindBufferMemory(context.device(), buffer_, memory_, 0), "vkBindBufferMemory");
    check(vkMapMemory(context.device(), memory_, 0, VK_WHOLE_SIZE, 0, &mapped_), "vkMapMemory");
  } catch (...) {
    if (memory_) vkFreeMemory(context.device(), memory_, nullptr);
    vkDestroyBuffer(context.device(), buffer_, nullptr);
    throw;
  }
}

Buffer::~Buffer() {
  vkUnmapMemory(context_.device(), memory_);
  vkFreeMemory(context_.device(), memory_, nullptr);
  vkDestroyBuffer(context_.device(), buffer_, nullptr);
}

Buffer& reuse(Context& context, std::unique_ptr<Buffer>& slot, uint64_t bytes, HostAccess access) {
  if (!slot || slot->bytes() < bytes) {
    slot.reset();  // free the old one first: two big buffers may not fit together
    slot = std::make_unique<Buffer>(context, bytes, access);
  }
  return *slot;
}

}  // namespace uvpress::engine::vk
