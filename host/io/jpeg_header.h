// What a JPEG's encoder chose, read from its markers: the quantization tables (and the IJG
// quality that best reproduces them), the chroma subsampling and whether it is progressive.
// A re-baked texture is written with the same choices, so it costs what the input's
// author accepted for it, not what a fixed quality 95 costs.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace uvpress::io {

struct JpegHeader {
  bool valid = false;       // a frame header (SOFn) was found
  int components = 0;       // 1 grey, 3 YCbCr (4: CMYK, written back as RGB)
  int h_sampling = 1, v_sampling = 1;  // the first component's factors; 2, 2 is 4:2:0
  bool progressive = false;            // SOF2
  int quality = 0;  // the IJG quality (1..100) whose scaled standard tables are nearest; 0: no tables
  // Quantization tables in natural (row-major) order, as DQT gave them; `table_of[c]` is
  // the table component c uses.
  std::array<std::array<uint16_t, 64>, 4> tables{};
  std::array<bool, 4> have_table{};
  std::array<int, 4> table_of{};
};

// Reads markers up to the first scan (no pixels are decoded). Malformed or truncated data
// gives valid == false; it never reads past `size`.
JpegHeader read_jpeg_header(const uint8_t* bytes, size_t size);

// The IJG quality (libjpeg's jpeg_set_quality scale, 1..100) whose luminance and
// chrominance tables are nearest to `luma` and `chroma` (null: luminance only), in the sum
// of absolute differences. Exact for files libjpeg wrote; the nearest scale for others.
int estimate_jpeg_quality(const std::array<uint16_t, 64>& luma, const std::array<uint16_t, 64>* chroma);

}  // namespace uvpress::io
