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

// GMSD step 1 on a decoded texture: Y = 0.299 R + 0.587 G + 0.114 B on the stored values
// (grey images: the value itself; alpha ignored).
inline std::vector<float> luminance_plane(const Image& image) {
  std::vector<float> y(size_t(image.width) * image.height);
  for (size_t i = 0; i < y.size(); ++i) {
    const float* px = &image.pixels[i * image.channels];
    y[i] = image.channels >= 3 ? 0.299f * px[0] + 0.587f * px[1] + 0.114f * px[2] : px[0];
  }
  return y;
}

}  // namespace uvpress
