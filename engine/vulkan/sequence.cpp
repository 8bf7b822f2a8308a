// Many dispatches per command buffer, one submit and one fence per batch: on lavapipe a
// submit costs about as much as a small dispatch, on GPUs far more.
#include "compute.h"

#include <vector>

namespace uvpress::engine::vk {

Sequence::Sequence(Context& context, uint32_t max_dispatches) : context_(context), max_dispatches_(max_dispatches) {
  VkDevice dev = context.device();
  try {
  auto cpci = make<VkCommandPoolCreateInfo>(VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO);
  cpci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  cpci.queueFamilyIndex = context.queue_family();
  check(vkCreateCommandPool(dev, &cpci, nullptr, &pool_), "vkCreateCommandPool");
  auto cbai = make<VkCommandBufferAllocateInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO);
  cbai.commandPool = pool_;
  cbai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  cbai.commandBufferCount = 1;
  check(vkAllocateCommandBuffers(dev, &cbai, &commands_), "vkAllocateCommandBuffers");
  // Up to 8 storage buffers per dispatch.
  VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 8 * max_dispatches};
  auto dpci = make<VkDescriptorPoolCreateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO);
  dpci.maxSets = max_dispatches;
  dpci.poolSizeCount = 1;
  dpci.pPoolSizes = &size;
  check(vkCreateDescriptorPool(dev, &dpci, nullptr, &descriptors_), "vkCreateDescriptorPool");
  auto fci = make<VkFenceCreateInfo>(VK_STRUCTURE_TYPE_FENCE_CREATE_INFO);
  check(vkCreateFence(dev, &fci, nullptr, &fence_), "vkCreateFence");
  } catch (...) {
    release();
    throw;
  }
}

Sequence::~Sequence() { release(); }

void Sequence::release() {  // vkDestroy* ignore null handles
  VkDevice dev = context_.device();
  vkDestroyFence(dev, fence_, nullptr);
  vkDestroyDescriptorPool(dev, descriptors_, nullptr);
  vkDestroyCommandPool(dev, pool_, nullptr);
}

void Sequence::begin() {
  check(vkResetDescriptorPool(context_.device(), descriptors_, 0), "vkResetDescriptorPool");
  check(vkResetCommandBuffer(commands_, 0), "vkResetCommandBuffer");
  auto bi = make<VkCommandBufferBeginInfo>(VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO);
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  check(vkBeginCommandBuffer(commands_, &bi), "vkBeginCommandBuffer");
  dispatches_ = 0;
}

void Sequence::dispatch(const Kernel& kernel, std::initializer_list<const Buffer*> buffers, const void* push,
                        uint32_t gx, uint32_t gy, uint32_t gz) {
  if (buffers.size() != kernel.buffers_) throw EngineError("Vulkan: kernel bound with the wrong number of buffers");
  if (buffers.size() > 8) throw EngineError("Vulkan: more than 8 buffers in one dispatch");
  if (dispatches_ == max_dispatches_) throw EngineError("Vulkan: too many dispatches in one sequence");
  const auto& lim = context_.limits().maxComputeWorkGroupCount;
  if (gx > lim[0] || gy > lim[1] || gz > lim[2]) throw EngineError("Vulkan: dispatch exceeds maxComputeWorkGroupCount");
  if (gx == 0 || gy == 0 || gz == 0) return;

  auto dsai = make<VkDescriptorSetAllocateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO);
  dsai.descriptorPool = descriptors_;
  dsai.descriptorSetCount = 1;
  dsai.pSetLayouts = &kernel.set_layout_;
  VkDescriptorSet set;
  check(vkAllocateDescriptorSets(context_.device(), &dsai, &set), "vkAllocateDescriptorSets");
  VkDescriptorBufferInfo infos[8];
  VkWriteDescriptorSet writes[8];
  uint32_t i = 0;
  for (const Buffer* b : buffers) {
    infos[i] = {b->handle(), 0, VK_WHOLE_SIZE};
    writes[i] = make<VkWriteDescriptorSet>(VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET);
    writes[i].dstSet = set;
    writes[i].dstBinding = i;
    writes[i].descriptorCount = 1;
    writes[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    writes[i].pBufferInfo = &infos[i];
    ++i;
  }
  vkUpdateDescriptorSets(context_.device(), i, writes, 0, nullptr);

  vkCmdBindPipeline(commands_, VK_PIPELINE_BIND_POINT_COMPUTE, kernel.pipeline_);
  vkCmdBindDescriptorSets(commands_, VK_PIPELINE_BIND_POINT_COMPUTE, kernel.layout_, 0, 1, &set, 0, nullptr);
  if (kernel.push_bytes_)
    vkCmdPushConstants(commands_, kernel.layout_, VK_SHADER_STAGE_COMPUTE_BIT, 0, kernel.push_bytes_, push);
  vkCmdDispatch(commands_, gx, gy, gz);
  ++dispatches_;
}

void Sequence::barrier() {
  auto mb = make<VkMemoryBarrier>(VK_STRUCTURE_TYPE_MEMORY_BARRIER);
  mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  mb.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
  vkCmdPipelineBarrier(commands_, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1,
                       &mb, 0, nullptr, 0, nullptr);
}

void Sequence::submit_and_wait() {
  auto mb = make<VkMemoryBarrier>(VK_STRUCTURE_TYPE_MEMORY_BARRIER);
  mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(commands_, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &mb, 0,
                       nullptr, 0, nullptr);
  check(vkEndCommandBuffer(commands_), "vkEndCommandBuffer");
  auto si = make<VkSubmitInfo>(VK_STRUCTURE_TYPE_SUBMIT_INFO);
  si.commandBufferCount = 1;
  si.pCommandBuffers = &commands_;
  check(vkResetFences(context_.device(), 1, &fence_), "vkResetFences");
  check(vkQueueSubmit(context_.queue(), 1, &si, fence_), "vkQueueSubmit");
  check(vkWaitForFences(context_.device(), 1, &fence_, VK_TRUE, UINT64_MAX), "vkWaitForFences");
}

}  // namespace uvpress::engine::vk
