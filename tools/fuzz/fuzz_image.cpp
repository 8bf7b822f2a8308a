// Image reader (libpng and libjpeg behind uvpress's checks, io/image_decode.h): sniffing, header, full decode,
// and the encoder settings read from the bytes (a JPEG's tables, a PNG's palette).
#include "core/error.h"
#include "io/image_io.h"

#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<uint8_t> bytes(data, data + size);
  try {
    (void)uvpress::io::encode_settings_of(bytes);
    auto h = uvpress::io::read_image_header(bytes, "fuzz");
    // Decode only what is cheap: a declared 16K x 16K image is a legal 4 GiB of floats.
    if (uint64_t(h.width) * h.height <= (1u << 20)) uvpress::io::decode_image(bytes, "fuzz");
  } catch (const uvpress::InputError&) {
  }
  return 0;
}
