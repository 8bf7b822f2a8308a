// JPEG writing through libjpeg directly: the quality, chroma subsampling and progressive
// mode a texture's input had (io/jpeg_header.h), and optimized Huffman tables (smaller at
// no loss). OpenImageIO's writer sets the quality only.
#pragma once

#include "core/image.h"

#include <cstdint>
#include <vector>

namespace uvpress::io {

struct JpegOptions {
  int quality = 95;                    // IJG scale, 1..100
  int h_sampling = 2, v_sampling = 2;  // luma factors against chroma at 1x1: 2, 2 is 4:2:0; 1, 1 is 4:4:4
  bool progressive = false;
};

// 1- and 2-channel images are written grey, 3 and 4 as YCbCr (JPEG has no alpha: it is
// dropped). Stored values as they are.
std::vector<uint8_t> encode_jpeg(const Image& image, const JpegOptions& options);

}  // namespace uvpress::io
