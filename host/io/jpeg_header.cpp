#include "io/jpeg_header.h"

#include <cstdlib>
#include <limits>

namespace uvpress::io {

namespace {

// Position k of the zig-zag sequence a DQT stores -> index in natural order.
constexpr int kNaturalOrder[64] = {0,  1,  8,  16, 9,  2,  3,  10, 17, 24, 32, 25, 18, 11, 4,  5,
                                   12, 19, 26, 33, 40, 48, 41, 34, 27, 20, 13, 6,  7,  14, 21, 28,
                                   35, 42, 49, 56, 57, 50, 43, 36, 29, 22, 15, 23, 30, 37, 44, 51,
                                   58, 59, 52, 45, 38, 31, 39, 46, 53, 60, 61, 54, 47, 55, 62, 63};

// The JPEG standard's example tables (ITU T.81 Annex K), natural order: what libjpeg scales.
constexpr uint16_t kStdLuma[64] = {16, 11, 10, 16, 24,  40,  51,  61,  12, 12, 14, 19, 26,  58,  60,  55,
                                   14, 13, 16, 24, 40,  57,  69,  56,  14, 17, 22, 29, 51,  87,  80,  62,
                                   18, 22, 37, 56, 68,  109, 103, 77,  24, 35, 55, 64, 81,  104, 113, 92,
                                   49, 64, 78, 87, 103, 121, 120, 101, 72, 92, 95, 98, 112, 100, 103, 99};
constexpr uint16_t kStdChroma[64] = {17, 18, 24, 47, 99, 99, 99, 99, 18, 21, 26, 66, 99, 99, 99, 99,
                                     24, 26, 56, 99, 99, 99, 99, 99, 47, 66, 99, 99, 99, 99, 99, 99,
                                     99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99,
                                     99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99};

// libjpeg's jpeg_quality_scaling and jpeg_add_quant_table (force_baseline: at most 255).
long scaled(uint16_t base, int quality) {
  const long scale = quality < 50 ? 5000 / quality : 200 - quality * 2;
  long v = (long(base) * scale + 50) / 100;
  return v < 1 ? 1 : v > 255 ? 255 : v;
}

}  // namespace

int estimate_jpeg_quality(const std::array<uint16_t, 64>& luma, const std::array<uint16_t, 64>* chroma) {
  int best = 0;
  long best_error = std::numeric_limits<long>::max();
  for (int q = 1; q <= 100; ++q) {
    long error = 0;
    for (int i = 0; i < 64; ++i) {
      error += std::labs(scaled(kStdLuma[i], q) - long(luma[size_t(i)]));
      if (chroma) error += std::labs(scaled(kStdChroma[i], q) - long((*chroma)[size_t(i)]));
    }
    // Ties (tables clamped at 1 near q 100) go to the lower quality: the cheaper file.
    if (error < best_error) best_error = error, best = q;
  }
  return best;
}

JpegHeader read_jpeg_header(const uint8_t* b, size_t n) {
  JpegHeader h;
  if (n < 4 || b[0] != 0xff || b[1] != 0xd8) return h;
  size_t at = 2;
  while (at + 4 <= n) {
    if (b[at] != 0xff) return h;
    const uint8_t marker = b[at + 1];
    if (marker == 0xff) {  // fill byte
      ++at;
      continue;
    }
    if (marker == 0xd8 || (marker >= 0xd0 && marker <= 0xd7) || marker == 0x01) {  // no length
      at += 2;
      continue;
    }
    const size_t length = size_t(b[at + 2]) << 8 | b[at + 3];
    if (length < 2 || at + 2 + length > n) return h;
    const uint8_t* p = b + at + 4;
    const size_t len = length - 2;
    if (marker == 0xdb) {  // DQT: one or more tables
      size_t k = 0;
      while (k < len) {
        const int precision = p[k] >> 4, id = p[k] & 15;
        const size_t bytes = precision ? 128 : 64;
        if (id > 3 || k + 1 + bytes > len) return h;
        for (int i = 0; i < 64; ++i)
          h.tables[size_t(id)][size_t(kNaturalOrder[i])] =
              precision ? uint16_t(p[k + 1 + 2 * size_t(i)] << 8 | p[k + 2 + 2 * size_t(i)]) : p[k + 1 + size_t(i)];
        h.have_table[size_t(id)] = true;
        k += 1 + bytes;
      }
    } else if (marker >= 0xc0 && marker <= 0xcf && marker != 0xc4 && marker != 0xc8 && marker != 0xcc) {  // SOFn
      if (len < 6) return h;
      h.components = p[5];
      if (h.components < 1 || len < 6 + 3 * size_t(h.components)) return h;
      for (int c = 0; c < h.components && c < 4; ++c) h.table_of[size_t(c)] = p[6 + 3 * c + 2] & 3;
      h.h_sampling = p[6 + 1] >> 4, h.v_sampling = p[6 + 1] & 15;
      h.progressive = marker == 0xc2 || marker == 0xc6 || marker == 0xca || marker == 0xce;
      h.valid = true;
    } else if (marker == 0xda) {  // the first scan: every table it needs is defined by now
      break;
    }
    at += 2 + length;
  }
  if (!h.valid) return h;
  const int luma = h.table_of[0];
  if (h.have_table[size_t(luma)]) {
    const int chroma = h.components >= 3 ? h.table_of[1] : -1;
    const bool has_chroma = chroma >= 0 && h.have_table[size_t(chroma)];
    h.quality = estimate_jpeg_quality(h.tables[size_t(luma)], has_chroma ? &h.tables[size_t(chroma)] : nullptr);
  }
  return h;
}

}  // namespace uvpress::io
