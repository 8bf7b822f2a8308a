// PNG and JPEG reading through libpng and libjpeg directly. The texels are those
// OpenImageIO gave uvpress before (so outputs keep their bits), while a process no longer
// loads OpenImageIO's ~260 libraries to start (~0.4 s for every command).
#pragma once

#include "core/image.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace uvpress::io {

// The decoder's reason a file does not decode, on one line.
struct DecodeError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
// A side over the caller's limit, found in the header before the texels are allocated.
struct ImageTooLarge : DecodeError {
  ImageTooLarge(uint32_t width, uint32_t height, uint32_t max_side)
      : DecodeError("image is " + std::to_string(width) + "x" + std::to_string(height) + ", larger than the supported " +
                    std::to_string(max_side) + " per side") {}
};

// A stored unsigned value as float in [0,1]: v times the reciprocal of the largest value,
// as OpenImageIO converts (which differs from v / 255 in the last bit for some v).
inline float unorm_to_float(uint32_t v, uint32_t largest) { return float(v) * (1.0f / float(largest)); }

// A big-endian 32-bit value, as PNG stores its chunk lengths and IHDR's sides.
inline uint32_t read_be32(const uint8_t* p) { return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3]; }

// PNG (io/png_decode.cpp): palettes expand to RGB, tRNS to an alpha channel, 1/2/4-bit
// grey to 8 bits; 16 bits stay 16; no gamma is applied and alpha stays straight. Fills
// width, height, channels (1 grey, 2 grey+alpha, 3 RGB, 4 RGBA) and bits (8 or 16), and
// the texels unless `header_only`. Sides over `max_side` throw ImageTooLarge. libpng's
// warnings are not printed; its errors throw DecodeError. Chunks after the image data are
// not read (OpenImageIO read them for interlaced files only, and refused a damaged tail).
Image decode_png(const uint8_t* bytes, size_t size, bool header_only, uint32_t max_side);

// A paletted PNG's palette (PLTE, with tRNS's alpha; 255 where tRNS says nothing), in
// entry order; empty for any other PNG, and for bytes libpng cannot read up to the image data.
std::vector<std::array<uint8_t, 4>> read_png_palette(const uint8_t* bytes, size_t size);

// JPEG (io/jpeg_decode.cpp): libjpeg's default decode (islow IDCT, fancy upsampling) to
// grey or RGB, 8 bits; CMYK and YCCK files become RGB as C*K, M*K, Y*K of the stored
// (inverted) values. Entropy-coded data that ends before the image does is an error
// (OpenImageIO filled the rest with grey); a file that lacks only its EOI marker decodes;
// other damage libjpeg skips with a warning decodes as it did through OpenImageIO.
Image decode_jpeg(const uint8_t* bytes, size_t size, bool header_only, uint32_t max_side);

}  // namespace uvpress::io
