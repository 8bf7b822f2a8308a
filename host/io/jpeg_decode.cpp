// JPEG decoding (io/image_decode.h). libjpeg reports errors by longjmp, so each step that
// can fail runs in a function whose frame holds only plain data (no destructor is skipped),
// and the buffers live in the caller.
#include "io/image_decode.h"

#include <jpeglib.h>
#include <jerror.h>

#include <algorithm>
#include <array>
#include <csetjmp>
#include <cstdio>
#include <string>
#include <vector>

namespace uvpress::io {

namespace {

struct JpegErrorSink {
  jpeg_error_mgr pub;  // first: libjpeg sees only this
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX] = {0};
};

[[noreturn]] void jpeg_fail(j_common_ptr cinfo) {
  auto* sink = reinterpret_cast<JpegErrorSink*>(cinfo->err);
  cinfo->err->format_message(cinfo, sink->message);
  std::longjmp(sink->jump, 1);
}
// libjpeg's warnings. Entropy-coded data that ends before the image does fails the decode:
// the rest would be made-up grey, and a clear error is better than silent texels. The
// input always ends in an EOI marker here (decode_jpeg adds one where it is cut off), so
// missing data shows as the decoder meeting a marker where it needs bits (JWRN_HIT_MARKER;
// it warns only when the bits are needed, not on read-ahead) or as the input running out
// (JWRN_JPEG_EOF). Other damage libjpeg skips (extraneous bytes, a segment it
// resynchronizes after) decodes as it did through OpenImageIO. Every warning comes here,
// not only the first (as output_message).
void on_jpeg_message(j_common_ptr cinfo, int level) {
  if (level < 0 && (cinfo->err->msg_code == JWRN_JPEG_EOF || cinfo->err->msg_code == JWRN_HIT_MARKER)) jpeg_fail(cinfo);
}

struct JpegLayout {
  uint32_t width = 0, height = 0;
  int components = 0;  // what libjpeg writes per texel (4 for CMYK)
  bool cmyk = false;
};

bool read_jpeg_frame(jpeg_decompress_struct* cinfo, JpegErrorSink* sink, const uint8_t* bytes, size_t size, JpegLayout* out) {
  if (setjmp(sink->jump)) return false;
  jpeg_mem_src(cinfo, bytes, static_cast<unsigned long>(size));
  jpeg_read_header(cinfo, TRUE);
  out->cmyk = cinfo->jpeg_color_space == JCS_CMYK || cinfo->jpeg_color_space == JCS_YCCK;
  if (out->cmyk) cinfo->out_color_space = JCS_CMYK;  // YCCK to CMYK by libjpeg, to RGB below
  out->width = cinfo->image_width, out->height = cinfo->image_height;
  return true;
}

// The output layout; with `decode`, the decoder started too. Only a header is wanted
// without it: jpeg_start_decompress reads a progressive file's every scan into a whole-image
// coefficient buffer (16384² x 3 components x 2 bytes = 1.5 GB for a declared 16384 x 16384).
bool start_jpeg(jpeg_decompress_struct* cinfo, JpegErrorSink* sink, bool decode, JpegLayout* out) {
  if (setjmp(sink->jump)) return false;
  if (decode)
    jpeg_start_decompress(cinfo);
  else
    jpeg_calc_output_dimensions(cinfo);
  out->components = cinfo->output_components;
  return true;
}

bool read_jpeg_rows(jpeg_decompress_struct* cinfo, JpegErrorSink* sink, JSAMPARRAY rows, uint32_t height) {
  if (setjmp(sink->jump)) return false;
  while (cinfo->output_scanline < height) {
    JSAMPARRAY at = rows + cinfo->output_scanline;
    if (jpeg_read_scanlines(cinfo, at, height - cinfo->output_scanline) == 0) return false;
  }
  return true;
}

bool create_jpeg(jpeg_decompress_struct* cinfo, JpegErrorSink* sink) {
  if (setjmp(sink->jump)) return false;
  jpeg_create_decompress(cinfo);  // can fail: out of memory, a library version mismatch
  return true;
}

struct JpegDecompress {
  jpeg_decompress_struct cinfo;
  JpegErrorSink sink;
  bool created = false;
  JpegDecompress() {
    cinfo.err = jpeg_std_error(&sink.pub);
    sink.pub.error_exit = jpeg_fail;
    sink.pub.emit_message = on_jpeg_message;
    cinfo.mem = nullptr;  // jpeg_destroy_decompress of a failed create frees nothing
    created = create_jpeg(&cinfo, &sink);
  }
  ~JpegDecompress() { jpeg_destroy_decompress(&cinfo); }
};

}  // namespace

Image decode_jpeg(const uint8_t* bytes, size_t size, bool header_only, uint32_t max_side) {
  // A file cut after its last entropy-coded byte (no EOI, or a lone 0xFF of it) holds every
  // texel: it gets its EOI, so only data that is really missing trips a warning (as it was,
  // libjpeg's read-ahead ran past the end and reported the file short).
  std::vector<uint8_t> ended;
  if (size < 2 || bytes[size - 2] != 0xff || bytes[size - 1] != 0xd9) {
    ended.assign(bytes, bytes + size);
    if (ended.empty() || ended.back() != 0xff) ended.push_back(0xff);
    ended.push_back(0xd9);
    bytes = ended.data(), size = ended.size();
  }
  JpegDecompress d;  // after `ended`: destroyed before the bytes it reads
  if (!d.created) throw DecodeError(d.sink.message);
  JpegLayout layout;
  if (!read_jpeg_frame(&d.cinfo, &d.sink, bytes, size, &layout)) throw DecodeError(d.sink.message);
  if (layout.width > max_side || layout.height > max_side) throw ImageTooLarge(layout.width, layout.height, max_side);
  if (!start_jpeg(&d.cinfo, &d.sink, !header_only, &layout)) throw DecodeError(d.sink.message);
  if (layout.cmyk ? layout.components != 4 : layout.components != 1 && layout.components != 3)
    throw DecodeError("unsupported colour layout (" + std::to_string(layout.components) + " components)");
  Image image;
  image.width = layout.width, image.height = layout.height, image.bits = 8;
  image.channels = layout.cmyk ? 3 : uint32_t(layout.components);
  if (header_only) return image;

  const size_t row_bytes = size_t(layout.width) * size_t(layout.components);
  std::vector<JSAMPLE> stored(row_bytes * layout.height);
  std::vector<JSAMPROW> rows(layout.height);
  for (size_t y = 0; y < rows.size(); ++y) rows[y] = stored.data() + y * row_bytes;
  if (!read_jpeg_rows(&d.cinfo, &d.sink, rows.data(), layout.height))
    throw DecodeError(d.sink.message[0] ? d.sink.message : "no more scanlines");

  std::array<float, 256> value;
  for (uint32_t v = 0; v < 256; ++v) value[v] = unorm_to_float(v, 255);
  const size_t texels = size_t(image.width) * image.height;
  image.pixels.resize(texels * image.channels);
  if (!layout.cmyk) {
    for (size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = value[stored[i]];
    return image;
  }
  // Adobe's CMYK is stored inverted (255 is no ink): R = C K etc. in [0,1], rounded to
  // 8 bits as OpenImageIO did.
  for (size_t i = 0; i < texels; ++i) {
    const JSAMPLE* cmyk = &stored[4 * i];
    const float k = value[cmyk[3]];
    for (int c = 0; c < 3; ++c) {
      const float r = std::clamp(value[cmyk[c]] * k * 255.0f + 0.5f, 0.0f, 255.0f);
      image.pixels[3 * i + size_t(c)] = value[uint8_t(r)];
    }
  }
  return image;
}

}  // namespace uvpress::io
