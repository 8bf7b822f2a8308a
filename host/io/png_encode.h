// PNG writing through libpng directly: several row-filter choices tried (adaptive per row,
// none, Paeth only), each one's filtered rows deflated again by libdeflate at level 12
// (~10 % below zlib's level 9), the smallest file kept. OpenImageIO's PNG writer offers
// neither the filter choice nor a palette.
#pragma once

#include "core/image.h"

#include <array>
#include <cstdint>
#include <vector>

namespace uvpress::io {

struct PngOptions {
  // Quantize to an 8-bit palette (libimagequant; io/palette_quantize.h). For inputs that
  // were paletted; ignored for 16-bit images.
  bool palette = false;
  float dithering = 1.0f;  // Floyd-Steinberg strength for a new palette (libimagequant's default)
  // With palette: the input's own palette (RGBA), and no other colour. A re-baked image is
  // drawn from the input's colours but filtering blends them; each blend takes its nearest
  // entry, undithered (dithering noise costs bytes, and the input's own art has none).
  // reparam --cost 0.5, against a new palette: Duck's texture 12,349 -> 9,859 bytes (0.61 of
  // the input's; 8,940 with libdeflate) at q 0.000281 -> 0.000292 (eval's noise floor
  // 0.00014); CesiumMilkTruck's, with libdeflate too, 335,699 -> 236,810 (0.55) at q 0.0123
  // -> 0.0128 (floor 0.00048; the resize, encoded alike, 0.0167).
  std::vector<std::array<uint8_t, 4>> fixed_palette;
  // Otherwise, an 8-bit palette all the same where it is faithful: quantized without
  // dithering, its RMS error over the written samples at most kFaithfulPaletteRms 8-bit
  // levels (else the image's own channels). Flat art and images of at most 256 colours pass
  // (Fox's re-baked texture: 0.33 levels, 72 -> 34 KB, q unchanged to three digits;
  // MultiUVTest's: lossless), smooth colour does not (the demo's: 1.7 levels, q 0.0176 ->
  // 0.0189). For truecolour 8-bit inputs (EncodeSettings).
  bool palette_when_faithful = false;
  // A new palette's weights: per texel (width * height, row-major) how much its colour counts
  // in the palette's fit (libimagequant's importance map, 0-255) and in the faithful test's
  // RMS; empty, or not width * height: all alike. reparam gives the texels a chart's bilinear
  // taps read full weight and the gutter, which coarse mip levels alone see (and average),
  // little: with coarsen_gutter's flat blocks (atlas/gutter_fill.h) Fox's gutters bring
  // colours of their own, and fitted alike they took entries from the charts (q 0.00165 ->
  // 0.00171; weighted 1 in 16, 0.00167).
  std::vector<uint8_t> importance;
  // One fast pass (zlib's fastest level, no row filter, no libdeflate) instead of the
  // strongest of three:
  // the same texels in larger bytes, for files that are decoded and scored but not written
  // (reparam's candidates).
  bool draft = false;
};

constexpr double kFaithfulPaletteRms = 0.5;

// Stored values as they are (no colour conversion). An alpha channel whose every texel is
// opaque is not written (grey+alpha -> grey, RGBA -> RGB; a palette gets no tRNS chunk).
std::vector<uint8_t> encode_png(const Image& image, const PngOptions& options);

}  // namespace uvpress::io
