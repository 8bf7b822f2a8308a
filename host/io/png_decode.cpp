// PNG decoding (io/image_decode.h). libpng reports errors by longjmp, so each step that can
// fail runs in a function whose frame holds only plain data (no destructor is skipped), and
// the buffers live in the caller.
#include "io/image_decode.h"

#include <png.h>

#include <array>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <new>
#include <string>
#include <vector>

namespace uvpress::io {

namespace {

struct PngSource {
  const uint8_t* data = nullptr;
  size_t size = 0, at = 0;
  char error[200] = {0};
};

void read_png_bytes(png_structp png, png_bytep out, png_size_t n) {
  auto* src = static_cast<PngSource*>(png_get_io_ptr(png));
  if (n > src->size - src->at) png_error(png, "the file ends early");
  std::memcpy(out, src->data + src->at, n);
  src->at += n;
}
void on_png_read_error(png_structp png, png_const_charp message) {
  auto* src = static_cast<PngSource*>(png_get_error_ptr(png));
  std::snprintf(src->error, sizeof src->error, "%s", message);
  png_longjmp(png, 1);
}
void on_png_read_warning(png_structp, png_const_charp) {}

// No ancillary chunk changes the texels (no gamma or colour conversion is applied), so
// libpng skips them unread rather than allocating what they declare: its tEXt handler
// allocated and zeroed a declared 1 GiB before finding the file 367 bytes long (the
// fuzzer's find: 8 s). tRNS is kept: it becomes the alpha channel.
void skip_ancillary_chunks(png_structp png) {
  static const png_byte skipped[] = "bKGD\0cHRM\0eXIf\0gAMA\0hIST\0iCCP\0iTXt\0oFFs\0pCAL\0pHYs\0sBIT\0sCAL\0sPLT\0sRGB\0tEXt\0tIME\0zTXt";
  png_set_keep_unknown_chunks(png, PNG_HANDLE_CHUNK_NEVER, skipped, int(sizeof skipped / 5));
}

struct PngLayout {
  png_uint_32 width = 0, height = 0;
  int bit_depth = 0, channels = 0;
  size_t row_bytes = 0;
};

// The header, and the transforms that give OpenImageIO's texels: png_set_expand (palette
// to RGB, tRNS to alpha, low-bit grey to 8 bits), 16-bit samples left big-endian. The
// caller has checked the sides (IHDR is the first chunk: libpng refuses a file without it
// there).
bool read_png_layout(png_structp png, png_infop info, PngLayout* out) {
  if (setjmp(png_jmpbuf(png))) return false;
  skip_ancillary_chunks(png);
  png_read_info(png, info);
  out->width = png_get_image_width(png, info);
  out->height = png_get_image_height(png, info);
  png_set_expand(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  out->bit_depth = png_get_bit_depth(png, info);
  out->channels = png_get_channels(png, info);
  out->row_bytes = png_get_rowbytes(png, info);
  return true;
}

// The rows. libpng checks the image data's zlib stream to its end with the last row; the
// chunks after it (metadata, IEND) are not read (OpenImageIO read them for interlaced
// files only).
bool read_png_rows(png_structp png, png_bytepp rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_image(png, rows);
  return true;
}

// PLTE and tRNS, read with the header (both come before the image data).
bool read_png_palette_chunks(png_structp png, png_infop info, std::vector<std::array<uint8_t, 4>>* out) {
  if (setjmp(png_jmpbuf(png))) return false;
  skip_ancillary_chunks(png);
  png_read_info(png, info);
  if (png_get_color_type(png, info) != PNG_COLOR_TYPE_PALETTE) return true;
  png_colorp colours = nullptr;
  int count = 0;
  if (!png_get_PLTE(png, info, &colours, &count) || !colours || count <= 0) return true;
  png_bytep alpha = nullptr;
  int alphas = 0;
  png_color_16p unused = nullptr;
  if (!png_get_tRNS(png, info, &alpha, &alphas, &unused)) alpha = nullptr, alphas = 0;
  for (int i = 0; i < count && i < 256; ++i)
    out->push_back({colours[i].red, colours[i].green, colours[i].blue, alpha && i < alphas ? alpha[i] : png_byte(255)});
  return true;
}

// A libpng reader over `src` (which outlives it).
struct PngReadStruct {
  png_structp png = nullptr;
  png_infop info = nullptr;
  explicit PngReadStruct(PngSource* src) {
    png = png_create_read_struct(PNG_LIBPNG_VER_STRING, src, on_png_read_error, on_png_read_warning);
    if (png) info = png_create_info_struct(png);
    if (!png || !info) {
      png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
      throw std::bad_alloc();
    }
    png_set_read_fn(png, src, read_png_bytes);
  }
  PngReadStruct(const PngReadStruct&) = delete;
  PngReadStruct& operator=(const PngReadStruct&) = delete;
  ~PngReadStruct() { png_destroy_read_struct(&png, info ? &info : nullptr, nullptr); }
};

}  // namespace

Image decode_png(const uint8_t* bytes, size_t size, bool header_only, uint32_t max_side) {
  // The declared size first, from IHDR's bytes: a file cut after its header still says
  // how large it claims to be (libpng reads on to the first IDAT before it tells), and
  // libpng's row buffers are never sized for more.
  if (size >= 24 && std::memcmp(bytes + 12, "IHDR", 4) == 0) {
    const uint32_t w = read_be32(bytes + 16), h = read_be32(bytes + 20);
    if (w > max_side || h > max_side) throw ImageTooLarge(w, h, max_side);
  }
  PngSource src;
  src.data = bytes, src.size = size;
  PngReadStruct rs(&src);

  PngLayout layout;
  if (!read_png_layout(rs.png, rs.info, &layout)) throw DecodeError(src.error);
  if (layout.width == 0 || layout.height == 0 || layout.channels < 1 || layout.channels > 4 ||
      (layout.bit_depth != 8 && layout.bit_depth != 16) ||
      layout.row_bytes != size_t(layout.width) * size_t(layout.channels) * size_t(layout.bit_depth / 8))
    throw DecodeError("unexpected layout after expansion");
  Image image;
  image.width = layout.width, image.height = layout.height;
  image.channels = uint32_t(layout.channels), image.bits = uint32_t(layout.bit_depth);
  if (header_only) return image;

  std::vector<uint8_t> stored(layout.row_bytes * layout.height);
  std::vector<png_bytep> rows(layout.height);
  for (size_t y = 0; y < rows.size(); ++y) rows[y] = stored.data() + y * layout.row_bytes;
  if (!read_png_rows(rs.png, rows.data())) throw DecodeError(src.error);

  image.pixels.resize(size_t(image.width) * image.height * image.channels);
  if (image.bits == 8) {
    std::array<float, 256> value;
    for (uint32_t v = 0; v < 256; ++v) value[v] = unorm_to_float(v, 255);
    for (size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = value[stored[i]];
  } else {
    for (size_t i = 0; i < image.pixels.size(); ++i)
      image.pixels[i] = unorm_to_float(uint32_t(stored[2 * i]) << 8 | stored[2 * i + 1], 65535);
  }
  return image;
}

std::vector<std::array<uint8_t, 4>> read_png_palette(const uint8_t* bytes, size_t size) {
  PngSource src;
  src.data = bytes, src.size = size;
  PngReadStruct rs(&src);
  std::vector<std::array<uint8_t, 4>> palette;
  if (!read_png_palette_chunks(rs.png, rs.info, &palette)) palette.clear();
  return palette;
}

}  // namespace uvpress::io
