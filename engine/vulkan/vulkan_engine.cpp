// The Vulkan backend of the Engine interface: kernels created once, buffers kept and
// reused across calls, batches chunked to the device's buffer limit, every chunk one
// command buffer with many dispatches and one fence.
#include "compute.h"
#include "layout.h"

#include "downsample2x2.spv.h"
#include "luminance.spv.h"

#include <algorithm>
#include <cstring>
#include <memory>

namespace uvpress::engine {
namespace {

using shader::ImageBatchPush;

constexpr uint32_t kLocal = 16;  // 16x16 invocations: 256 threads, fine on GPUs and lavapipe

uint32_t groups(uint32_t n, uint32_t local) { return (n + local - 1) / local; }

class VulkanEngine final : public Engine {
 public:
  VulkanEngine(DeviceRequest request, const EngineOptions& options)
      : context_(request, options.validation),
        max_buffer_(options.max_buffer_bytes ? std::min(options.max_buffer_bytes, context_.max_buffer_bytes())
                                             : context_.max_buffer_bytes()),
        luminance_(context_, luminance_spv, sizeof(luminance_spv), 2, sizeof(ImageBatchPush), kLocal, kLocal),
        downsample_(context_, downsample2x2_spv, sizeof(downsample2x2_spv), 2, sizeof(ImageBatchPush), kLocal,
                    kLocal),
        sequence_(context_) {}

  DeviceInfo device() const override { return context_.info(); }
  uint64_t validation_errors() const override { return context_.validation_errors(); }

  LuminanceBatch luminance(const Rgba8Batch& b) override {
    const uint64_t n = uint64_t(b.width) * b.height;
    const uint64_t n2 = uint64_t((b.width + 1) / 2) * ((b.height + 1) / 2);
    LuminanceBatch out;
    out.full.resize(n * b.count);
    out.half.resize(n2 * b.count);
    if (b.count == 0 || n == 0) return out;
    // RGBA8 in and float out are both 4 bytes a pixel: one image costs 4n bytes per buffer.
    const uint64_t per_chunk = std::min<uint64_t>(b.count, max_buffer_ / (4 * n));
    if (per_chunk == 0) throw EngineError("Vulkan: one image is larger than the device's largest buffer");
    vk::Buffer& rgba = buffer(rgba_, 4 * n * per_chunk);
    vk::Buffer& full = buffer(full_, 4 * n * per_chunk);
    vk::Buffer& half = buffer(half_, 4 * n2 * per_chunk);
    const uint32_t max_z = context_.limits().maxComputeWorkGroupCount[2];

    for (uint64_t first = 0; first < b.count; first += per_chunk) {
      const uint32_t count = uint32_t(std::min<uint64_t>(per_chunk, b.count - first));
      std::memcpy(rgba.data<uint32_t>(), b.pixels + first * n, 4 * n * count);
      sequence_.begin();
      for (uint32_t z = 0; z < count; z += max_z) {
        ImageBatchPush push{b.width, b.height, z, std::min(max_z, count - z)};
        sequence_.dispatch(luminance_, {&rgba, &full}, &push, groups(b.width, kLocal), groups(b.height, kLocal),
                           push.count);
      }
      sequence_.barrier();
      for (uint32_t z = 0; z < count; z += max_z) {
        ImageBatchPush push{b.width, b.height, z, std::min(max_z, count - z)};
        sequence_.dispatch(downsample_, {&full, &half}, &push, groups((b.width + 1) / 2, kLocal),
                           groups((b.height + 1) / 2, kLocal), push.count);
      }
      sequence_.submit_and_wait();
      std::memcpy(out.full.data() + first * n, full.data<float>(), 4 * n * count);
      std::memcpy(out.half.data() + first * n2, half.data<float>(), 4 * n2 * count);
    }
    return out;
  }

 private:
  // Keeps a buffer across calls and grows it only when a call needs more.
  vk::Buffer& buffer(std::unique_ptr<vk::Buffer>& slot, uint64_t bytes) {
    if (!slot || slot->bytes() < bytes) {
      slot.reset();
      slot = std::make_unique<vk::Buffer>(context_, bytes);
    }
    return *slot;
  }

  vk::Context context_;
  uint64_t max_buffer_;
  vk::Kernel luminance_, downsample_;
  vk::Sequence sequence_;
  std::unique_ptr<vk::Buffer> rgba_, full_, half_;
};

}  // namespace

std::unique_ptr<Engine> make_vulkan_engine(DeviceRequest request, const EngineOptions& options) {
  if (request != DeviceRequest::Gpu && request != DeviceRequest::Lavapipe)
    throw EngineError("make_vulkan_engine takes --device gpu or lavapipe");
  return std::make_unique<VulkanEngine>(request, options);
}

}  // namespace uvpress::engine
