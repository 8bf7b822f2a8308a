// uvpress decodes PNG and JPEG with libpng and libjpeg directly (io/image_decode.h); these
// cases hold it to OpenImageIO's decode, which it replaced, float for float: every shared
// texture, every PNG colour type and bit depth (palettes, tRNS, low-bit grey, 16 bits,
// Adam7, a gAMA chunk), JPEG grey, subsampled, progressive, CMYK and YCCK, and damaged
// files, which must fail where OpenImageIO failed, and where a JPEG's data ends early (it
// made up the missing texels), and decode the same otherwise (a JPEG without its EOI too).
#include <catch2/catch.hpp>

#include "core/error.h"
#include "io/atomic_file.h"
#include "io/image_io.h"
#include "io/jpeg_encode.h"
#include "support.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <jpeglib.h>
#include <png.h>

#include <cmath>
#include <chrono>
#include <csetjmp>
#include <cstring>
#include <random>
#include <string>
#include <vector>

using namespace uvpress;

namespace {

struct Decoded {
  bool ok = false;
  Image image;
  std::string error;  // ours: the InputError's message
};

// The reference: OpenImageIO as image_io.cpp used it (in memory, straight alpha, float).
Decoded oiio_decode(const std::vector<uint8_t>& bytes, bool png) {
  OIIO::Filesystem::IOMemReader proxy(bytes.data(), bytes.size());
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  void* proxy_ptr = &proxy;
  config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy_ptr);
  auto in = OIIO::ImageInput::open(png ? "memory.png" : "memory.jpg", &config, &proxy);
  Decoded d;
  if (!in) {
    (void)OIIO::geterror();
    return d;
  }
  const OIIO::ImageSpec& s = in->spec();
  d.image.width = uint32_t(s.width), d.image.height = uint32_t(s.height), d.image.channels = uint32_t(s.nchannels);
  d.image.bits = s.format.size() >= 2 ? 16 : 8;
  d.image.pixels.resize(size_t(s.width) * size_t(s.height) * size_t(s.nchannels));
  d.ok = in->read_image(0, 0, 0, s.nchannels, OIIO::TypeDesc::FLOAT, d.image.pixels.data());
  (void)in->geterror();
  return d;
}

Decoded ours(const std::vector<uint8_t>& bytes) {
  Decoded d;
  try {
    d.image = io::decode_image(bytes, "test");
    d.ok = true;
  } catch (const InputError& e) {
    d.error = e.what();
  }
  return d;
}

// The same texels, bit for bit, and the same header (what read_image_header says, too).
void check_same(const std::vector<uint8_t>& bytes, const std::string& what) {
  INFO(what);
  const bool png = io::sniff_image_format(bytes.data(), bytes.size()) == "png";
  const Decoded ref = oiio_decode(bytes, png);
  REQUIRE(ref.ok);
  const Image img = io::decode_image(bytes, what);
  const io::ImageHeader h = io::read_image_header(bytes, what);
  CHECK(h.width == ref.image.width);
  CHECK(h.height == ref.image.height);
  CHECK(h.channels == ref.image.channels);
  CHECK(h.bits == ref.image.bits);
  REQUIRE(img.width == ref.image.width);
  REQUIRE(img.height == ref.image.height);
  REQUIRE(img.channels == ref.image.channels);
  CHECK(img.bits == ref.image.bits);
  REQUIRE(img.pixels.size() == ref.image.pixels.size());
  size_t differ = 0;
  for (size_t i = 0; i < img.pixels.size(); ++i) differ += std::memcmp(&img.pixels[i], &ref.image.pixels[i], sizeof(float)) != 0;
  CHECK(differ == 0);
}

// A PNG written by libpng with every choice open: bit depth, colour type, tRNS, Adam7,
// a gAMA chunk. Random samples (packed as the bit depth says).
struct PngSpec {
  uint32_t width = 23, height = 17;
  int depth = 8, color_type = PNG_COLOR_TYPE_RGB;
  bool interlaced = false, trns = false, gamma = false;
  uint32_t seed = 1;
};

struct PngSink {
  std::vector<uint8_t>* bytes;
};

void sink_write(png_structp png, png_bytep data, png_size_t n) {
  auto* sink = static_cast<PngSink*>(png_get_io_ptr(png));
  sink->bytes->insert(sink->bytes->end(), data, data + n);
}
void sink_flush(png_structp) {}

// Plain data only in this frame (libpng's errors longjmp to it).
bool write_png(const PngSpec& spec, const png_color* palette, const png_byte* alpha, const png_color_16* trans,
               png_bytepp rows, PngSink* sink) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, info ? &info : nullptr);
    return false;
  }
  png_set_write_fn(png, sink, sink_write, sink_flush);
  png_set_IHDR(png, info, spec.width, spec.height, spec.depth, spec.color_type,
               spec.interlaced ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_BASE, PNG_FILTER_TYPE_BASE);
  if (spec.color_type == PNG_COLOR_TYPE_PALETTE) png_set_PLTE(png, info, palette, 1 << spec.depth);
  if (spec.trns) png_set_tRNS(png, info, alpha, spec.color_type == PNG_COLOR_TYPE_PALETTE ? 3 : 0, trans);
  if (spec.gamma) png_set_gAMA(png, info, 1.0);  // "linear": no decoder may convert
  png_write_info(png, info);
  png_write_image(png, rows);
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return true;
}

std::vector<uint8_t> make_png(const PngSpec& spec) {
  const int channels = spec.color_type == PNG_COLOR_TYPE_GRAY || spec.color_type == PNG_COLOR_TYPE_PALETTE ? 1
                       : spec.color_type == PNG_COLOR_TYPE_GRAY_ALPHA                                       ? 2
                       : spec.color_type == PNG_COLOR_TYPE_RGB                                              ? 3
                                                                                                            : 4;
  const size_t row_bytes = (size_t(spec.width) * size_t(channels) * size_t(spec.depth) + 7) / 8;
  std::mt19937 rng(spec.seed);
  std::vector<uint8_t> data(row_bytes * spec.height);
  for (auto& b : data) b = uint8_t(rng());
  std::vector<png_bytep> rows(spec.height);
  for (size_t y = 0; y < rows.size(); ++y) rows[y] = data.data() + y * row_bytes;
  std::vector<png_color> palette(256);
  for (auto& p : palette) p = {uint8_t(rng()), uint8_t(rng()), uint8_t(rng())};
  const png_byte alpha[3] = {0, 77, 200};
  // A transparent colour that occurs: the first texel's (grey: its top bits as a value).
  png_color_16 trans{};
  trans.gray = spec.depth == 16 ? png_uint_16(data[0] << 8 | data[1]) : png_uint_16(data[0] >> (8 - spec.depth));
  if (spec.depth == 16)
    trans.red = png_uint_16(data[0] << 8 | data[1]), trans.green = png_uint_16(data[2] << 8 | data[3]),
    trans.blue = png_uint_16(data[4] << 8 | data[5]);
  else
    trans.red = data[0], trans.green = data[1], trans.blue = data[2];
  std::vector<uint8_t> bytes;
  PngSink sink{&bytes};
  REQUIRE(write_png(spec, palette.data(), alpha, &trans, rows.data(), &sink));
  return bytes;
}

// A 4-component JPEG written by libjpeg: Adobe CMYK, or YCCK.
std::vector<uint8_t> make_cmyk_jpeg(bool ycck) {
  jpeg_compress_struct cinfo;
  jpeg_error_mgr err;
  cinfo.err = jpeg_std_error(&err);
  jpeg_create_compress(&cinfo);
  unsigned char* out = nullptr;
  unsigned long size = 0;
  jpeg_mem_dest(&cinfo, &out, &size);
  cinfo.image_width = 40, cinfo.image_height = 24, cinfo.input_components = 4, cinfo.in_color_space = JCS_CMYK;
  jpeg_set_defaults(&cinfo);
  if (ycck) jpeg_set_colorspace(&cinfo, JCS_YCCK);
  jpeg_set_quality(&cinfo, 90, TRUE);
  jpeg_start_compress(&cinfo, TRUE);
  std::vector<JSAMPLE> row(40 * 4);
  while (cinfo.next_scanline < cinfo.image_height) {
    for (uint32_t x = 0; x < 40; ++x)
      for (uint32_t c = 0; c < 4; ++c) row[x * 4 + c] = JSAMPLE((x * 7 + cinfo.next_scanline * (c + 3) * 5 + c * 60) % 256);
    JSAMPROW r = row.data();
    jpeg_write_scanlines(&cinfo, &r, 1);
  }
  jpeg_finish_compress(&cinfo);
  jpeg_destroy_compress(&cinfo);
  std::vector<uint8_t> bytes(out, out + size);
  free(out);
  return bytes;
}

using test::smooth_image;

}  // namespace

TEST_CASE("Every shared texture decodes as OpenImageIO decoded it, float for float", "[io][image][shared]") {
  auto shared = test::shared_dir();
  if (!shared) UVPRESS_SKIP("../shared is absent");
  size_t files = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(*shared / "assets")) {
    if (!entry.is_regular_file()) continue;
    const auto bytes = io::read_file(entry.path().string());
    const std::string format = io::sniff_image_format(bytes.data(), bytes.size());
    if (format != "png" && format != "jpeg") continue;
    check_same(bytes, entry.path().string());
    ++files;
  }
  CHECK(files >= 5);
}

TEST_CASE("Every PNG colour type and bit depth decodes as OpenImageIO decoded it", "[io][image]") {
  struct Case {
    int color_type;
    std::vector<int> depths;
  };
  const std::vector<Case> cases = {{PNG_COLOR_TYPE_GRAY, {1, 2, 4, 8, 16}},
                                   {PNG_COLOR_TYPE_GRAY_ALPHA, {8, 16}},
                                   {PNG_COLOR_TYPE_RGB, {8, 16}},
                                   {PNG_COLOR_TYPE_RGB_ALPHA, {8, 16}},
                                   {PNG_COLOR_TYPE_PALETTE, {1, 2, 4, 8}}};
  uint32_t seed = 1;
  for (const Case& c : cases)
    for (int depth : c.depths)
      for (int variant = 0; variant < 3; ++variant) {
        PngSpec spec;
        spec.color_type = c.color_type, spec.depth = depth, spec.seed = seed++;
        spec.trns = variant == 1 && !(c.color_type & PNG_COLOR_MASK_ALPHA);
        spec.interlaced = variant == 2, spec.gamma = variant == 2;
        check_same(make_png(spec), "PNG colour type " + std::to_string(c.color_type) + ", " + std::to_string(depth) +
                                       " bits, variant " + std::to_string(variant));
      }
}

TEST_CASE("JPEG grey, subsampled, progressive, CMYK and YCCK decode as OpenImageIO decoded them", "[io][image]") {
  const std::vector<std::pair<uint32_t, io::JpegOptions>> cases = {
      {3, {90, 2, 2, false}}, {3, {75, 1, 1, true}}, {3, {60, 2, 1, false}}, {1, {85, 1, 1, false}}, {1, {70, 1, 1, true}}};
  for (const auto& [channels, options] : cases) {
    io::EncodeSettings s;
    s.format = "jpeg", s.jpeg_quality = options.quality, s.progressive = options.progressive;
    s.jpeg_h_sampling = options.h_sampling, s.jpeg_v_sampling = options.v_sampling;
    check_same(io::encode_image(smooth_image(61, 45, channels), s), "JPEG " + io::describe(s) + ", " + std::to_string(channels) + " channels");
  }
  check_same(make_cmyk_jpeg(false), "CMYK JPEG");
  check_same(make_cmyk_jpeg(true), "YCCK JPEG");
}

TEST_CASE("Damaged PNG and JPEG files fail where OpenImageIO failed or a JPEG's data ends early, and decode the same otherwise",
          "[io][image]") {
  PngSpec palette;
  palette.color_type = PNG_COLOR_TYPE_PALETTE, palette.trns = true;
  io::EncodeSettings progressive;
  progressive.format = "jpeg", progressive.progressive = true;
  const std::vector<std::vector<uint8_t>> files = {
      io::encode_image(smooth_image(64, 48, 3), "png"), make_png(palette),
      io::encode_image(smooth_image(64, 48, 3), "jpeg"), io::encode_image(smooth_image(64, 48, 3), progressive)};
  size_t failures = 0, cases = 0;
  for (size_t f = 0; f < files.size(); ++f) {
    const auto& whole = files[f];
    std::vector<std::vector<uint8_t>> damaged;
    for (double keep : {0.1, 0.5, 0.9}) damaged.emplace_back(whole.begin(), whole.begin() + long(double(whole.size()) * keep));
    damaged.emplace_back(whole.begin(), whole.end() - 1);  // a JPEG's EOI cut to its 0xFF
    damaged.emplace_back(whole.begin(), whole.end() - 2);  // a JPEG without its EOI
    for (size_t at : {whole.size() / 3, whole.size() / 2, whole.size() * 3 / 4}) {
      damaged.push_back(whole);
      damaged.back()[at] ^= 0x5a;
    }
    for (size_t d = 0; d < damaged.size(); ++d) {
      INFO("file " << f << ", damage " << d);
      const bool png = f < 2;
      const Decoded ref = oiio_decode(damaged[d], png);
      const Decoded got = ours(damaged[d]);
      // A JPEG cut inside its entropy-coded data is refused (OpenImageIO filled its missing
      // texels with grey); one that lacks only its EOI marker holds every texel and decodes.
      // A byte flipped into a marker ends the data early too: refused, with libjpeg's reason.
      const bool cut_jpeg = !png && d < 3;
      INFO(got.error);
      if (!png && d >= 5 && ref.ok && !got.ok)
        CHECK_THAT(got.error, Catch::Contains("premature end", Catch::CaseSensitive::No));
      else
        CHECK(got.ok == (ref.ok && !cut_jpeg));
      if (!png && (d == 3 || d == 4)) {
        REQUIRE(got.ok);
        const Image intact = io::decode_image(whole, "intact.jpg");
        CHECK(std::memcmp(got.image.pixels.data(), intact.pixels.data(), intact.pixels.size() * sizeof(float)) == 0);
      }
      if (got.ok && ref.ok) {
        REQUIRE(got.image.pixels.size() == ref.image.pixels.size());
        CHECK(std::memcmp(got.image.pixels.data(), ref.image.pixels.data(), got.image.pixels.size() * sizeof(float)) == 0);
      }
      failures += !got.ok, ++cases;
    }
  }
  CHECK(failures >= cases / 2);  // truncation always fails: these cases test refusals, not only agreement
}

TEST_CASE("A header is read without allocating what the file declares", "[io][image]") {
  using clock = std::chrono::steady_clock;
  // A PNG whose first chunk after IHDR declares 1 GiB of tEXt, in a file of a few hundred
  // bytes: libpng's text handler allocated and zeroed the declared size (8 s); now skipped.
  auto png = io::encode_image(smooth_image(8, 8, 3), "png");
  const uint8_t chunk[] = {0x40, 0x00, 0x00, 0x00, 't', 'E', 'X', 't', 'k', 'e', 'y', 0, 'v'};
  png.insert(png.begin() + 33, chunk, chunk + sizeof chunk);  // after the signature and IHDR (8 + 25 bytes)
  auto start = clock::now();
  CHECK_THROWS_WITH(io::decode_image(png, "big-text.png"), Catch::Contains("corrupt png image"));
  CHECK(std::chrono::duration<double>(clock::now() - start).count() < 1.0);
  // A progressive JPEG whose frame header says 16384 x 16384: its header reads at once
  // (starting the decoder would allocate the whole image's coefficients and read every scan).
  io::EncodeSettings progressive;
  progressive.format = "jpeg", progressive.progressive = true;
  auto jpeg = io::encode_image(smooth_image(16, 16, 3), progressive);
  size_t sof = 2;
  while (sof + 9 < jpeg.size() && !(jpeg[sof] == 0xff && jpeg[sof + 1] == 0xc2)) ++sof;
  REQUIRE(sof + 9 < jpeg.size());
  jpeg[sof + 5] = 0x40, jpeg[sof + 6] = 0x00, jpeg[sof + 7] = 0x40, jpeg[sof + 8] = 0x00;  // height, width
  start = clock::now();
  const io::ImageHeader h = io::read_image_header(jpeg, "big.jpg");
  CHECK(std::chrono::duration<double>(clock::now() - start).count() < 1.0);
  CHECK(h.width == 16384);
  CHECK(h.height == 16384);
  CHECK(h.channels == 3);
}
