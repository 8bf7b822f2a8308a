#include "io/jpeg_encode.h"

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include <jpeglib.h>

namespace uvpress::io {

namespace {

struct ErrorManager {
  jpeg_error_mgr base;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void on_error(j_common_ptr cinfo) {
  auto* err = reinterpret_cast<ErrorManager*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, err->message);
  std::longjmp(err->jump, 1);
}
void on_message(j_common_ptr) {}

// Only plain data in this frame: libjpeg's error path longjmps out of it.
bool write_jpeg(const uint8_t* samples, uint32_t width, uint32_t height, int components, const JpegOptions& o,
                unsigned char** out, unsigned long* out_size, char* message) {
  jpeg_compress_struct cinfo;
  ErrorManager err;
  cinfo.err = jpeg_std_error(&err.base);
  err.base.error_exit = on_error;
  err.base.output_message = on_message;
  if (setjmp(err.jump)) {
    std::snprintf(message, JMSG_LENGTH_MAX, "%s", err.message);
    jpeg_destroy_compress(&cinfo);
    return false;
  }
  jpeg_create_compress(&cinfo);
  jpeg_mem_dest(&cinfo, out, out_size);
  cinfo.image_width = width, cinfo.image_height = height;
  cinfo.input_components = components;
  cinfo.in_color_space = components == 1 ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_set_defaults(&cinfo);
  jpeg_set_quality(&cinfo, std::clamp(o.quality, 1, 100), TRUE);
  if (components == 3) {
    cinfo.comp_info[0].h_samp_factor = std::clamp(o.h_sampling, 1, 4);
    cinfo.comp_info[0].v_samp_factor = std::clamp(o.v_sampling, 1, 4);
    for (int c = 1; c < 3; ++c) cinfo.comp_info[c].h_samp_factor = cinfo.comp_info[c].v_samp_factor = 1;
  }
  cinfo.optimize_coding = TRUE;
  if (o.progressive) jpeg_simple_progression(&cinfo);
  jpeg_start_compress(&cinfo, TRUE);
  const size_t stride = size_t(width) * size_t(components);
  while (cinfo.next_scanline < cinfo.image_height) {
    JSAMPROW row = const_cast<JSAMPROW>(samples + size_t(cinfo.next_scanline) * stride);
    jpeg_write_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_compress(&cinfo);
  jpeg_destroy_compress(&cinfo);
  return true;
}

}  // namespace

std::vector<uint8_t> encode_jpeg(const Image& image, const JpegOptions& options) {
  if (image.width == 0 || image.height == 0 || image.channels == 0 || image.channels > 4 ||
      image.pixels.size() != size_t(image.width) * image.height * image.channels)
    throw std::invalid_argument("encode_jpeg: inconsistent image");
  const int components = image.channels >= 3 ? 3 : 1;
  const size_t n = size_t(image.width) * image.height;
  std::vector<uint8_t> samples(n * size_t(components));
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < components; ++c)
      samples[i * size_t(components) + size_t(c)] =
          uint8_t(std::lround(std::clamp(image.pixels[i * image.channels + size_t(c)], 0.0f, 1.0f) * 255.0f));
  unsigned char* out = nullptr;
  unsigned long size = 0;
  char message[JMSG_LENGTH_MAX] = {0};
  const bool ok = write_jpeg(samples.data(), image.width, image.height, components, options, &out, &size, message);
  std::vector<uint8_t> bytes;
  if (ok && out) bytes.assign(out, out + size);
  std::free(out);
  if (!ok) throw std::runtime_error(std::string("encoding jpeg failed: ") + message);
  return bytes;
}

}  // namespace uvpress::io
