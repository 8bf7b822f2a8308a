// Quantization of an RGBA8 image to at most 256 colours (libimagequant, pngquant's
// library): for inputs that were paletted PNGs, so that a re-baked texture is written in
// the form, and at about the size, its author chose. A re-baked image rarely has 256
// colours or fewer (filtering blends them), so this is lossy; the loss is part of what the
// written file scores.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace uvpress::io {

struct PaletteImage {
  std::vector<std::array<uint8_t, 4>> palette;  // RGBA, at most 256 entries
  std::vector<uint8_t> indices;                 // one per texel, row-major
};

// `rgba`: width * height * 4 bytes (straight alpha). Floyd-Steinberg dithering at
// `dithering` (0: none, 1: full). With `fixed` (at most 256 colours) the palette is those
// colours and no other, in their order: each texel takes the fixed colour libimagequant
// finds nearest (dithered as asked). `importance`, when not null (width * height, row-major):
// how much each texel's colour weighs in a new palette's fit (libimagequant's importance map,
// which then replaces the edge and noise weights libimagequant would derive itself; 0 is
// taken as 1, so that every texel counts a little). Throws std::runtime_error when
// libimagequant fails.
PaletteImage quantize_palette(const uint8_t* rgba, uint32_t width, uint32_t height, float dithering,
                              const std::vector<std::array<uint8_t, 4>>& fixed = {},
                              const std::vector<uint8_t>* importance = nullptr);

}  // namespace uvpress::io
