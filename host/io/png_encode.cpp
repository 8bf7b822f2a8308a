#include "io/png_encode.h"

#include "io/image_decode.h"
#include "io/palette_quantize.h"

#include <libdeflate.h>
#include <png.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

namespace uvpress::io {

namespace {

// What one libpng run writes: rows of `bytes_per_row` bytes (big-endian 16-bit samples).
struct Rows {
  uint32_t width = 0, height = 0;
  int bit_depth = 8, color_type = PNG_COLOR_TYPE_RGB;
  size_t bytes_per_row = 0;
  std::vector<uint8_t> data;
  std::vector<png_color> palette;
  std::vector<png_byte> alpha;  // tRNS: alpha of the first palette entries
  double rms = 0;               // palette: RMS error against the image's 8-bit samples, in 8-bit levels
};

struct Sink {
  std::vector<uint8_t> bytes;
  char error[200] = {0};
};

void write_bytes(png_structp png, png_bytep data, png_size_t n) {
  auto* sink = static_cast<Sink*>(png_get_io_ptr(png));
  sink->bytes.insert(sink->bytes.end(), data, data + n);
}
void flush(png_structp) {}
void on_error(png_structp png, png_const_charp message) {
  auto* sink = static_cast<Sink*>(png_get_error_ptr(png));
  std::snprintf(sink->error, sizeof sink->error, "%s", message);
  png_longjmp(png, 1);
}
void on_warning(png_structp, png_const_charp) {}

// One encode at one filter choice and zlib strategy. Only plain data lives in this frame,
// so the longjmp of libpng's error path skips no destructor.
bool write_png(const Rows& r, int filters, int level, int strategy, Sink* sink) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, sink, on_error, on_warning);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, info ? &info : nullptr);
    return false;
  }
  png_set_write_fn(png, sink, write_bytes, flush);
  png_set_compression_level(png, level);
  png_set_compression_mem_level(png, MAX_MEM_LEVEL);
  png_set_compression_strategy(png, strategy);
  png_set_filter(png, PNG_FILTER_TYPE_BASE, filters);
  png_set_IHDR(png, info, r.width, r.height, r.bit_depth, r.color_type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_BASE,
               PNG_FILTER_TYPE_BASE);
  if (r.color_type == PNG_COLOR_TYPE_PALETTE) {
    png_set_PLTE(png, info, r.palette.data(), int(r.palette.size()));
    if (!r.alpha.empty()) png_set_tRNS(png, info, r.alpha.data(), int(r.alpha.size()), nullptr);
  }
  png_write_info(png, info);
  if (r.color_type == PNG_COLOR_TYPE_PALETTE && r.bit_depth < 8) png_set_packing(png);  // one index a byte in
  for (uint32_t y = 0; y < r.height; ++y) png_write_row(png, r.data.data() + size_t(y) * r.bytes_per_row);
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return true;
}

bool opaque(const Image& img) {
  if (img.channels != 2 && img.channels != 4) return true;
  const float max = img.bits == 16 ? 65535.0f : 255.0f;
  const size_t n = size_t(img.width) * img.height;
  for (size_t i = 0; i < n; ++i)
    if (std::lround(std::clamp(img.pixels[i * img.channels + img.channels - 1], 0.0f, 1.0f) * max) < long(max)) return false;
  return true;
}

Rows palette_rows(const Image& img, bool keep_alpha, float dithering, const std::vector<std::array<uint8_t, 4>>& fixed,
                  const std::vector<uint8_t>& importance) {
  const size_t n = size_t(img.width) * img.height;
  std::vector<uint8_t> rgba(n * 4);
  auto to8 = [](float v) { return uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); };
  for (size_t i = 0; i < n; ++i) {
    const float* p = &img.pixels[i * img.channels];
    const bool grey = img.channels <= 2;
    for (int c = 0; c < 3; ++c) rgba[4 * i + size_t(c)] = to8(grey ? p[0] : p[c]);
    rgba[4 * i + 3] = keep_alpha ? to8(p[img.channels - 1]) : 255;
  }
  const bool weighted = importance.size() == n;
  PaletteImage q = quantize_palette(rgba.data(), img.width, img.height, fixed.empty() ? dithering : 0.0f, fixed,
                                    weighted ? &importance : nullptr);
  // Translucent entries first, so that tRNS lists only them.
  std::vector<uint8_t> order(q.palette.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = uint8_t(i);
  std::stable_sort(order.begin(), order.end(), [&](uint8_t a, uint8_t b) { return (q.palette[a][3] < 255) > (q.palette[b][3] < 255); });
  std::vector<uint8_t> slot(q.palette.size());
  Rows r;
  r.width = img.width, r.height = img.height, r.color_type = PNG_COLOR_TYPE_PALETTE;
  for (size_t k = 0; k < order.size(); ++k) {
    const auto& e = q.palette[order[k]];
    slot[order[k]] = uint8_t(k);
    r.palette.push_back({e[0], e[1], e[2]});
    if (e[3] < 255) r.alpha.push_back(e[3]);
  }
  const size_t colours = r.palette.size();
  r.bit_depth = colours <= 2 ? 1 : colours <= 4 ? 2 : colours <= 16 ? 4 : 8;
  r.bytes_per_row = img.width;  // one index a byte; png_set_packing packs lower depths
  r.data.resize(n);
  for (size_t i = 0; i < n; ++i) r.data[i] = slot[q.indices[i]];
  // Over the samples written (grey images compare their one channel, opaque ones no alpha),
  // each texel weighted by its importance where given.
  const int count = img.channels <= 2 ? 1 : 3;
  double sum = 0, weight = 0;
  for (size_t i = 0; i < n; ++i) {
    const auto& e = q.palette[q.indices[i]];
    double s = 0;
    for (int c = 0; c < count; ++c) s += (double(e[size_t(c)]) - rgba[4 * i + size_t(c)]) * (double(e[size_t(c)]) - rgba[4 * i + size_t(c)]);
    if (keep_alpha) s += (double(e[3]) - rgba[4 * i + 3]) * (double(e[3]) - rgba[4 * i + 3]);
    const double w = weighted ? std::max(1.0, double(importance[i])) : 1.0;
    sum += w * s, weight += w;
  }
  r.rms = std::sqrt(sum / (weight * (count + (keep_alpha ? 1 : 0))));
  return r;
}

Rows direct_rows(const Image& img, bool keep_alpha) {
  const uint32_t colour = img.channels >= 3 ? 3 : 1;
  const uint32_t out_channels = colour + (keep_alpha ? 1 : 0);
  Rows r;
  r.width = img.width, r.height = img.height;
  r.bit_depth = img.bits == 16 ? 16 : 8;
  r.color_type = colour == 3 ? (keep_alpha ? PNG_COLOR_TYPE_RGBA : PNG_COLOR_TYPE_RGB)
                             : (keep_alpha ? PNG_COLOR_TYPE_GRAY_ALPHA : PNG_COLOR_TYPE_GRAY);
  const size_t sample = r.bit_depth / 8;
  r.bytes_per_row = size_t(img.width) * out_channels * sample;
  r.data.resize(r.bytes_per_row * img.height);
  const float max = r.bit_depth == 16 ? 65535.0f : 255.0f;
  size_t at = 0;
  for (size_t i = 0; i < size_t(img.width) * img.height; ++i) {
    const float* p = &img.pixels[i * img.channels];
    for (uint32_t c = 0; c < out_channels; ++c) {
      const float v = c < colour ? p[c] : p[img.channels - 1];
      const uint32_t s = uint32_t(std::lround(std::clamp(v, 0.0f, 1.0f) * max));
      if (sample == 2) r.data[at++] = uint8_t(s >> 8);  // PNG is big-endian
      r.data[at++] = uint8_t(s);
    }
  }
  return r;
}

void put_be32(std::vector<uint8_t>& out, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(uint8_t(v >> s));
}

struct FreeCompressor {
  void operator()(libdeflate_compressor* c) const { libdeflate_free_compressor(c); }
};

// The image data of a PNG that libpng wrote (its IDAT chunks: one zlib stream of the
// filtered rows), deflated again by libdeflate at its strongest level, 12, whose
// near-optimal parsing zlib's level 9 lacks: the same rows, the same decoded texels, in
// ~6-10 % fewer bytes (Duck's re-baked palette image: 9,616 -> 8,703). False, and `png` as
// it was, where that is not smaller than the stream libpng wrote.
bool recompress_image_data(std::vector<uint8_t>& png) {
  // Chunks: length, type, data, CRC. libpng writes IHDR first and the IDATs in one run.
  size_t first = 0, last = 0;
  std::vector<uint8_t> stream;
  for (size_t at = 8; at + 12 <= png.size();) {
    const size_t n = read_be32(&png[at]);
    if (at + 12 + n > png.size()) return false;
    if (std::memcmp(&png[at + 4], "IDAT", 4) == 0) {
      if (!first) first = at;
      last = at + 12 + n;
      stream.insert(stream.end(), png.begin() + long(at + 8), png.begin() + long(at + 8 + n));
    }
    at += 12 + n;
  }
  if (!first || stream.empty() || png.size() < 33 || png[28] != PNG_INTERLACE_NONE) return false;
  // The filtered rows' size, from IHDR: a filter byte and ceil(width * bits a texel / 8).
  const uint32_t width = read_be32(&png[16]), height = read_be32(&png[20]);
  const int depth = png[24], colour = png[25];
  const int channels = colour == PNG_COLOR_TYPE_RGB ? 3 : colour == PNG_COLOR_TYPE_RGBA ? 4 : colour == PNG_COLOR_TYPE_GRAY_ALPHA ? 2 : 1;
  std::vector<uint8_t> rows(size_t(height) * (1 + (size_t(width) * size_t(channels * depth) + 7) / 8));
  uLongf got = uLongf(rows.size());
  if (uncompress(rows.data(), &got, stream.data(), uLong(stream.size())) != Z_OK || got != rows.size()) return false;
  std::unique_ptr<libdeflate_compressor, FreeCompressor> c(libdeflate_alloc_compressor(12));
  if (!c) return false;
  // Room for less than what libpng wrote: libdeflate gives 0 when it does not fit.
  std::vector<uint8_t> deflated(stream.size() - 1);
  const size_t size = libdeflate_zlib_compress(c.get(), rows.data(), rows.size(), deflated.data(), deflated.size());
  if (size == 0) return false;
  std::vector<uint8_t> out(png.begin(), png.begin() + long(first));
  // IDATs of at most 16 MiB (a chunk's length must stay below 2^31).
  for (size_t at = 0; at < size;) {
    const size_t n = std::min<size_t>(size - at, size_t(1) << 24);
    put_be32(out, uint32_t(n));
    const size_t type_at = out.size();
    out.insert(out.end(), {'I', 'D', 'A', 'T'});
    out.insert(out.end(), deflated.begin() + long(at), deflated.begin() + long(at + n));
    put_be32(out, uint32_t(crc32(0, out.data() + type_at, uInt(4 + n))));
    at += n;
  }
  out.insert(out.end(), png.begin() + long(last), png.end());
  png = std::move(out);
  return true;
}

}  // namespace

std::vector<uint8_t> encode_png(const Image& image, const PngOptions& options) {
  if (image.width == 0 || image.height == 0 || image.channels == 0 || image.channels > 4 ||
      image.pixels.size() != size_t(image.width) * image.height * image.channels)
    throw std::invalid_argument("encode_png: inconsistent image");
  const bool keep_alpha = !opaque(image);
  const bool palette = (options.palette || options.palette_when_faithful) && image.bits != 16;
  // The input's palette where it can hold the image: an opaque image takes its opaque entries
  // only (a translucent one would add transparency that was not there), a translucent image
  // all of them if any is translucent; otherwise a new palette.
  std::vector<std::array<uint8_t, 4>> fixed;
  if (options.palette) {
    for (const auto& e : options.fixed_palette)
      if (keep_alpha || e[3] == 255) fixed.push_back(e);
    if (keep_alpha && std::none_of(fixed.begin(), fixed.end(), [](const std::array<uint8_t, 4>& e) { return e[3] < 255; }))
      fixed.clear();
  }
  Rows rows = palette ? palette_rows(image, keep_alpha, options.palette ? options.dithering : 0.0f, fixed, options.importance)
                      : direct_rows(image, keep_alpha);
  if (!options.palette && palette && rows.rms > kFaithfulPaletteRms) rows = direct_rows(image, keep_alpha);
  // libpng's adaptive choice per row (minimum sum of absolute differences) is a heuristic:
  // on smooth colour it wins, on palettes and flat areas no filter often does. Try both,
  // and Paeth alone, and keep the smallest.
  const int filters[] = {PNG_ALL_FILTERS, PNG_FILTER_NONE, PNG_FILTER_PAETH};
  const size_t tries = options.draft ? 1 : 3;
  // zlib's fastest level where libdeflate deflates the rows again (recompress_image_data).
  const int level = Z_BEST_SPEED;
  std::vector<uint8_t> best;
  std::string error;
  for (size_t k = 0; k < tries; ++k) {
    const int f = options.draft ? PNG_FILTER_NONE : filters[k];
    Sink sink;
    if (!write_png(rows, f, level, Z_DEFAULT_STRATEGY, &sink)) {
      error = sink.error;
      continue;
    }
    // Where libdeflate gives nothing smaller (never seen), zlib's strongest level instead.
    if (!options.draft && !recompress_image_data(sink.bytes)) {
      sink.bytes.clear();
      if (!write_png(rows, f, Z_BEST_COMPRESSION, Z_DEFAULT_STRATEGY, &sink)) {
        error = sink.error;
        continue;
      }
    }
    if (best.empty() || sink.bytes.size() < best.size()) best = std::move(sink.bytes);
  }
  if (best.empty()) throw std::runtime_error("encoding png failed: " + error);
  return best;
}

}  // namespace uvpress::io
