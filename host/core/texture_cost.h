// What a texture costs a user besides its encoded bytes: texels, and GPU memory with a
// full mip chain, uncompressed (RGBA8, 4 bytes a texel) and block-compressed at one byte a
// texel (BC7, ASTC 4x4: 16-byte blocks of 4 x 4 texels, every level padded to whole
// blocks). The numbers a technical artist compares before and after.
#pragma once

#include <algorithm>
#include <cstdint>

namespace uvpress {

struct TextureCost {
  uint64_t texels = 0;
  uint64_t vram_rgba8 = 0;  // bytes, RGBA8 with the full mip chain (down to 1 x 1)
  uint64_t vram_bc7 = 0;    // bytes, 4 x 4 blocks of 16 bytes with the full mip chain
};

inline TextureCost texture_cost(uint32_t width, uint32_t height) {
  TextureCost c;
  c.texels = uint64_t(width) * height;
  for (uint64_t w = width, h = height;; w = std::max<uint64_t>(1, w / 2), h = std::max<uint64_t>(1, h / 2)) {
    c.vram_rgba8 += 4 * w * h;
    c.vram_bc7 += 16 * ((w + 3) / 4) * ((h + 3) / 4);
    if (w == 1 && h == 1) break;
  }
  return c;
}

}  // namespace uvpress
