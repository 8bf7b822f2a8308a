// The Vulkan backend's re-bake sampler (rebake.comp; the CPU twin is
// cpu/rebake_texels.cpp).
#pragma once

#include "compute.h"
#include "engine.h"
#include "layout.h"

#include <cmath>
#include <cstdint>
#include <memory>

namespace uvpress::engine {

// Its own kernel and buffers, made on first use. The working source goes whole, split by
// texel index over four buffers; the new image goes in chunks of tile rows whose list
// entries, owners and texels each fit one buffer, every chunk one submit of several
// dispatches (kRebakeDispatchRows tile rows each, so no dispatch runs long on a GPU).
class Rebaker {
 public:
  Rebaker(vk::Context& context, vk::Sequence& sequence, uint64_t max_buffer);

  // Fills texels (d.width x d.height x d.channels) for every owned texel (engine.h).
  void run(const RebakeTexelsDesc& d, float* texels);

 private:
  static constexpr uint32_t kRebakeDispatchRows = 8;

  static uint32_t wrap_code(int mode) {
    return mode == kRebakeWrapClampToEdge ? 1u : mode == kRebakeWrapMirroredRepeat ? 2u : 0u;
  }

  // x = hi + lo with hi on a grid of 2^-12 (see shader::RebakeEntry).
  static void split(double x, float& hi, float& lo) {
    hi = float(std::round(x * 4096.0) / 4096.0);
    lo = float(x - double(hi));
  }

  // Triangle t in the frame of the tile whose corner is (ox, oy), computed in double.
  static shader::RebakeEntry make_entry(const RebakeTriangle& t, double ox, double oy);


  vk::Context& context_;
  vk::Sequence& sequence_;
  uint64_t max_buffer_;
  vk::Kernel kernel_;
  std::unique_ptr<vk::Buffer> source_[4], dummy_, starts_, entries_, owner_, texels_;
};

}  // namespace uvpress::engine
