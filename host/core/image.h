// A decoded texture: values as stored in the file (sRGB-encoded for colour textures),
// normalized to [0,1], channels interleaved, row 0 at the top.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace uvpress {

enum class ColorSpace { Srgb, Linear };

struct Image {
  uint32_t width = 0, height = 0;
  uint32_t channels = 0;  // 1 grey, 2 grey+alpha, 3 RGB, 4 RGBA
  uint32_t bits = 8;      // bits per channel in the file it came from (8 or 16)
  std::vector<float> pixels;

  float at(uint32_t x, uint32_t y, uint32_t c) const { return pixels[(size_t(y) * width + x) * channels + c]; }
  float& at(uint32_t x, uint32_t y, uint32_t c) { return pixels[(size_t(y) * width + x) * channels + c]; }
};

}  // namespace uvpress
