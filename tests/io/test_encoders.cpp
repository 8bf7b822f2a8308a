// The tight encoders (issue 18): PNG palettes for paletted inputs (and for truecolour ones
// where the palette is faithful), no alpha channel when
// every texel is opaque, PNG at least as small as OpenImageIO's default writer, and the
// JPEG settings of an input (quality from its quantization tables, subsampling,
// progressive) read back from files written by another encoder.
#include <catch2/catch.hpp>

#include "io/atomic_file.h"
#include "io/image_io.h"
#include "io/jpeg_encode.h"
#include "io/jpeg_header.h"
#include "io/palette_quantize.h"
#include "io/png_encode.h"
#include "support.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

using namespace uvpress;

namespace {

using test::smooth_image;

// IHDR colour type: 0 grey, 2 RGB, 3 palette, 4 grey+alpha, 6 RGBA.
int png_color_type(const std::vector<uint8_t>& png) { return png.size() > 25 ? png[25] : -1; }

bool has_chunk(const std::vector<uint8_t>& png, const char* type) {
  for (size_t at = 8; at + 8 <= png.size();) {
    const uint32_t length = uint32_t(png[at]) << 24 | uint32_t(png[at + 1]) << 16 | uint32_t(png[at + 2]) << 8 | png[at + 3];
    if (std::equal(type, type + 4, png.begin() + long(at + 4))) return true;
    at += 12 + size_t(length);
  }
  return false;
}

double mean_difference(const Image& a, const Image& b, uint32_t channels) {
  double sum = 0;
  for (uint32_t y = 0; y < a.height; ++y)
    for (uint32_t x = 0; x < a.width; ++x)
      for (uint32_t c = 0; c < channels; ++c) sum += std::abs(a.at(x, y, c) - b.at(x, y, c));
  return sum / (double(a.width) * a.height * channels);
}

// The same image written by OpenImageIO (libjpeg's jpeg_set_quality through another code
// path than uvpress's encoder), or its PNG writer at its defaults.
std::vector<uint8_t> oiio_write(const Image& img, const char* name, const std::string& compression) {
  std::vector<uint8_t> out;
  OIIO::Filesystem::IOVecOutput proxy(out);
  auto writer = OIIO::ImageOutput::create(name, &proxy);
  REQUIRE(writer);
  OIIO::ImageSpec spec(int(img.width), int(img.height), int(img.channels), OIIO::TypeDesc::UINT8);
  if (!compression.empty()) spec.attribute("Compression", compression);
  REQUIRE(writer->open("memory", spec));
  REQUIRE(writer->write_image(OIIO::TypeDesc::FLOAT, img.pixels.data()));
  REQUIRE(writer->close());
  return out;
}

}  // namespace

TEST_CASE("PNG palette: a paletted input's re-encode is an 8-bit palette close to the source, smaller than RGB",
          "[io][encode]") {
  const Image img = smooth_image(96, 80, 3);
  io::EncodeSettings palette;
  palette.palette = true;
  const auto paletted = io::encode_image(img, palette), rgb = io::encode_image(img, "png");
  CHECK(png_color_type(paletted) == 3);
  CHECK_FALSE(has_chunk(paletted, "tRNS"));  // opaque: no transparency chunk
  CHECK(png_color_type(rgb) == 2);
  CHECK(paletted.size() < rgb.size());
  // The settings read back from the file say "palette": a reparam of the output keeps it.
  CHECK(io::encode_settings_of(paletted).palette);
  CHECK_FALSE(io::encode_settings_of(rgb).palette);
  const Image back = io::decode_image(paletted, "paletted");
  REQUIRE(back.channels == 3);
  std::set<std::array<float, 3>> colours;
  for (uint32_t y = 0; y < back.height; ++y)
    for (uint32_t x = 0; x < back.width; ++x) colours.insert({back.at(x, y, 0), back.at(x, y, 1), back.at(x, y, 2)});
  CHECK(colours.size() <= 256);
  CHECK(colours.size() > 16);
  CHECK(mean_difference(img, back, 3) < 0.04);  // quantized and dithered, not posterized (a wrong map: > 0.1)

  // Translucent texels keep their alpha through the palette's tRNS entries.
  Image rgba = smooth_image(64, 64, 4);
  for (uint32_t y = 0; y < 32; ++y)
    for (uint32_t x = 0; x < 64; ++x) rgba.at(x, y, 3) = 0.5f;
  const auto translucent = io::encode_image(rgba, palette);
  CHECK(png_color_type(translucent) == 3);
  CHECK(has_chunk(translucent, "tRNS"));
  const Image back4 = io::decode_image(translucent, "translucent");
  REQUIRE(back4.channels == 4);
  CHECK(std::abs(back4.at(10, 10, 3) - 0.5f) < 0.02f);
  CHECK(back4.at(10, 50, 3) == 1.0f);
}

namespace {

// Flat art: `cells` flat colours in Voronoi cells, each texel the mean of 4x4 samples, so
// the cells' borders are anti-aliased blends (several hundred colours in all, most texels
// one of the flat ones), as a re-baked cartoon texture is.
Image flat_art(uint32_t w, uint32_t h, int cells) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<std::array<float, 5>> seeds;  // x, y, r, g, b
  for (int k = 0; k < cells; ++k) seeds.push_back({u(rng) * float(w), u(rng) * float(h), u(rng), u(rng), u(rng)});
  Image img;
  img.width = w, img.height = h, img.channels = 3;
  img.pixels.assign(size_t(w) * h * 3, 0.0f);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x)
      for (int sy = 0; sy < 4; ++sy)
        for (int sx = 0; sx < 4; ++sx) {
          const float px = float(x) + (float(sx) + 0.5f) / 4, py = float(y) + (float(sy) + 0.5f) / 4;
          size_t best = 0;
          for (size_t k = 1; k < seeds.size(); ++k)
            if (std::hypot(px - seeds[k][0], py - seeds[k][1]) < std::hypot(px - seeds[best][0], py - seeds[best][1])) best = k;
          for (int c = 0; c < 3; ++c) img.at(x, y, uint32_t(c)) += seeds[best][2 + size_t(c)] / 16;
        }
  for (float& v : img.pixels) v = std::round(v * 255.0f) / 255.0f;  // 8-bit values, as decoded
  return img;
}

// RMS difference in 8-bit levels over the colour channels.
double rms_levels(const Image& a, const Image& b) {
  double sum = 0;
  for (uint32_t y = 0; y < a.height; ++y)
    for (uint32_t x = 0; x < a.width; ++x)
      for (uint32_t c = 0; c < 3; ++c) sum += std::pow(255.0 * (a.at(x, y, c) - b.at(x, y, c)), 2);
  return std::sqrt(sum / (double(a.width) * a.height * 3));
}

}  // namespace

TEST_CASE("PNG palette: a paletted input's own palette, no other colour, undithered: smaller than a new palette",
          "[io][encode]") {
  // The input: six flat colours in vertical bands, one of them translucent, as a paletted PNG.
  const std::array<std::array<float, 4>, 6> bands{{{0.9f, 0.8f, 0.1f, 1.0f}, {0.1f, 0.1f, 0.1f, 1.0f}, {1.0f, 1.0f, 1.0f, 1.0f},
                                                   {0.8f, 0.3f, 0.1f, 1.0f}, {0.2f, 0.5f, 0.9f, 1.0f}, {0.2f, 0.5f, 0.9f, 0.5f}}};
  Image in;
  in.width = 96, in.height = 40, in.channels = 4;
  for (uint32_t y = 0; y < in.height; ++y)
    for (uint32_t x = 0; x < in.width; ++x)
      for (float v : bands[x / 16]) in.pixels.push_back(std::round(v * 255.0f) / 255.0f);
  io::EncodeSettings fresh;
  fresh.palette = true;
  const auto input = io::encode_image(in, fresh);
  REQUIRE(png_color_type(input) == 3);
  const io::EncodeSettings settings = io::encode_settings_of(input);
  CHECK(settings.palette);
  REQUIRE(settings.palette_colours.size() == 6);
  CHECK(io::describe(settings) == "png (8-bit palette: the input's 6 colours)");
  CHECK(io::describe_encoded(input) == "png (8-bit palette)");  // a property of the bytes, not a choice
  std::set<std::array<uint8_t, 4>> entries(settings.palette_colours.begin(), settings.palette_colours.end());
  for (const auto& b : bands) {
    const std::array<uint8_t, 4> e{uint8_t(std::lround(b[0] * 255)), uint8_t(std::lround(b[1] * 255)),
                                   uint8_t(std::lround(b[2] * 255)), uint8_t(std::lround(b[3] * 255))};
    CHECK(entries.count(e) == 1);  // PLTE with tRNS's alpha, read back
  }
  // A "re-bake": the bands resampled, so their borders blend (a 7-texel box along x) and a
  // smooth ramp of brightness over the whole (the blends no palette entry holds).
  Image rebaked = in;
  for (uint32_t y = 0; y < in.height; ++y)
    for (uint32_t x = 0; x < in.width; ++x)
      for (uint32_t c = 0; c < 4; ++c) {
        float sum = 0;
        for (int d = -3; d <= 3; ++d) sum += in.at(uint32_t(std::clamp(int(x) + d, 0, int(in.width) - 1)), y, c);
        rebaked.at(x, y, c) = std::round(sum / 7 * 255.0f) / 255.0f;
      }
  const auto written = io::encode_image(rebaked, settings), anew = io::encode_image(rebaked, fresh);
  REQUIRE(png_color_type(written) == 3);
  const Image back = io::decode_image(written, "written");
  REQUIRE(back.channels == 4);
  size_t exact = 0, blended = 0;
  for (uint32_t y = 0; y < back.height; ++y)
    for (uint32_t x = 0; x < back.width; ++x) {
      std::array<uint8_t, 4> e;
      for (uint32_t c = 0; c < 4; ++c) e[c] = uint8_t(std::lround(back.at(x, y, c) * 255.0f));
      INFO("texel " << x << ", " << y);
      REQUIRE(entries.count(e) == 1);  // every texel one of the input's colours
      const bool inside = x % 16 >= 3 && x % 16 < 13;  // the box reads one band only
      if (inside) {
        ++exact;
        for (uint32_t c = 0; c < 4; ++c)  // an input colour stays itself
          CHECK(e[c] == std::lround(rebaked.at(x, y, c) * 255.0f));
      } else {
        ++blended;
      }
    }
  CHECK(exact > 0);
  CHECK(blended > 0);
  // Two texels from the border of yellow and near-black: one sixth of the way across each
  // takes its own side's colour, not a dithered mix.
  CHECK(std::lround(back.at(13, 0, 0) * 255.0f) == std::lround(in.at(0, 0, 0) * 255.0f));
  CHECK(std::lround(back.at(18, 0, 0) * 255.0f) == std::lround(in.at(16, 0, 0) * 255.0f));
  // No dithering noise: fewer bytes than a new palette for the same texels.
  INFO("input's palette " << written.size() << " bytes, a new palette " << anew.size());
  CHECK(written.size() < anew.size());

  // A fully transparent entry keeps its colour (libimagequant gives alpha-0 entries back as
  // black), and a one-entry palette (which libimagequant cannot make) is that entry alone.
  for (const bool one : {false, true}) {
    const std::string what = one ? "one entry" : "a transparent entry";
    INFO(what);
    Image p;
    p.width = 8, p.height = 4, p.channels = 4;
    for (uint32_t k = 0; k < p.width * p.height; ++k)
      for (float v : (one || k % 2 == 0) ? std::array<float, 4>{1, 1, 1, 0} : std::array<float, 4>{0.2f, 0.4f, 0.6f, 1})
        p.pixels.push_back(v);
    io::EncodeSettings ps = fresh;  // as read from such an input (a new palette would not keep alpha 0's white)
    ps.palette_colours = {{255, 255, 255, 0}};
    if (!one) ps.palette_colours.push_back({51, 102, 153, 255});
    Image mixed = p;  // a blend between the two, and the transparent white
    mixed.at(1, 0, 0) = 0.9f, mixed.at(1, 0, 3) = 0.1f;
    const Image b = io::decode_image(io::encode_image(mixed, ps), "again");
    REQUIRE(b.channels == 4);
    CHECK(b.at(0, 0, 0) == 1.0f);  // white, not black
    CHECK(b.at(0, 0, 3) == 0.0f);
    CHECK(b.at(1, 0, 0) == 1.0f);  // the nearer entry: transparent white
    if (!one) CHECK(std::lround(b.at(3, 0, 2) * 255) == std::lround(0.6f * 255));
  }
}

TEST_CASE("PNG image data deflated tighter than zlib's strongest level, the same filtered rows", "[io][encode]") {
  // The rows as libpng filtered them, deflated again by zlib at level 9 (memLevel 9): the
  // file's stream must be smaller, and inflate to the very same rows, for every form the
  // encoder writes (the rows' size is the file's own: IHDR's sides, depth and colour type).
  Image deep = smooth_image(160, 120, 3), translucent = smooth_image(160, 120, 4), grey_alpha = smooth_image(160, 120, 2);
  deep.bits = 16;
  for (Image* img : {&translucent, &grey_alpha})  // translucent: the alpha channel is written
    for (uint32_t y = 0; y < img->height; ++y)
      for (uint32_t x = 0; x < img->width; ++x) img->at(x, y, img->channels - 1) = float(64 + (x + y) % 128) / 255.0f;
  Image six = flat_art(192, 128, 6);  // a palette of at most 16 colours: 4-bit indices
  for (float& v : six.pixels) v = v < 0.5f ? 0.2f : 0.8f;
  io::EncodeSettings palette;
  palette.palette = true;
  struct Case {
    const char* what;
    Image img;
    io::EncodeSettings settings;
    int colour_type, depth;
  };
  for (const Case& c : {Case{"RGB", smooth_image(160, 120, 3), {}, 2, 8}, Case{"flat art", flat_art(192, 128, 10), {}, 2, 8},
                        Case{"RGB 16-bit", deep, {}, 2, 16}, Case{"RGBA", translucent, {}, 6, 8},
                        Case{"grey+alpha", grey_alpha, {}, 4, 8}, Case{"4-bit palette", six, palette, 3, 4}}) {
    INFO(c.what);
    const auto png = io::encode_image(c.img, c.settings);
    REQUIRE(png_color_type(png) == c.colour_type);
    REQUIRE(png[24] == c.depth);
    std::vector<uint8_t> stream;
    for (size_t at = 8; at + 12 <= png.size();) {
      const uint32_t n = uint32_t(png[at]) << 24 | uint32_t(png[at + 1]) << 16 | uint32_t(png[at + 2]) << 8 | png[at + 3];
      if (std::equal(png.begin() + long(at + 4), png.begin() + long(at + 8), "IDAT"))
        stream.insert(stream.end(), png.begin() + long(at + 8), png.begin() + long(at + 8 + n));
      at += 12 + n;
    }
    const int channels = c.colour_type == 2 ? 3 : c.colour_type == 6 ? 4 : c.colour_type == 4 ? 2 : 1;
    std::vector<uint8_t> rows(size_t(c.img.height) * (1 + (size_t(c.img.width) * size_t(channels * c.depth) + 7) / 8));
    uLongf got = uLongf(rows.size());
    REQUIRE(uncompress(rows.data(), &got, stream.data(), uLong(stream.size())) == Z_OK);
    REQUIRE(got == rows.size());
    z_stream z{};
    REQUIRE(deflateInit2(&z, 9, Z_DEFLATED, 15, 9, Z_DEFAULT_STRATEGY) == Z_OK);
    std::vector<uint8_t> zlib9(deflateBound(&z, uLong(rows.size())));
    z.next_in = rows.data(), z.avail_in = uInt(rows.size());
    z.next_out = zlib9.data(), z.avail_out = uInt(zlib9.size());
    REQUIRE(deflate(&z, Z_FINISH) == Z_STREAM_END);
    const size_t zlib9_size = z.total_out;
    deflateEnd(&z);
    INFO("image data " << stream.size() << " bytes, zlib level 9 " << zlib9_size);
    CHECK(stream.size() < zlib9_size);
    const Image back = io::decode_image(png, "png");
    CHECK(mean_difference(c.img, back, std::min(3u, c.img.channels)) < (c.colour_type == 3 ? 1e-6 : 1e-4));  // lossless
  }
}

TEST_CASE("PNG palette where faithful: flat art becomes a palette within half a level, smooth colour stays as it is",
          "[io][encode]") {
  io::EncodeSettings faithful;
  faithful.palette_when_faithful = true;
  // Flat art with anti-aliased borders: more than 256 colours, a palette all the same.
  const Image art = flat_art(256, 192, 12);
  std::set<std::array<float, 3>> colours;
  for (uint32_t y = 0; y < art.height; ++y)
    for (uint32_t x = 0; x < art.width; ++x) colours.insert({art.at(x, y, 0), art.at(x, y, 1), art.at(x, y, 2)});
  REQUIRE(colours.size() > 256);
  const auto art_png = io::encode_image(art, faithful), art_rgb = io::encode_image(art, "png");
  CHECK(png_color_type(art_png) == 3);
  CHECK(art_png.size() < art_rgb.size());
  const double art_rms = rms_levels(art, io::decode_image(art_png, "art"));
  INFO("flat art: " << colours.size() << " colours, palette RMS " << art_rms << " levels, " << art_png.size() << " vs "
                    << art_rgb.size() << " bytes as RGB");
  CHECK(art_rms <= io::kFaithfulPaletteRms);
  CHECK(art_rms > 0);  // lossy, within the bound
  // Translucent flat art: its alpha goes through the palette's tRNS entries, within the bound.
  Image art4;
  art4.width = art.width, art4.height = art.height, art4.channels = 4;
  for (uint32_t y = 0; y < art.height; ++y)
    for (uint32_t x = 0; x < art.width; ++x) {
      for (uint32_t c = 0; c < 3; ++c) art4.pixels.push_back(art.at(x, y, c));
      art4.pixels.push_back(x < art.width / 2 ? 1.0f : 128.0f / 255.0f);
    }
  const auto art4_png = io::encode_image(art4, faithful);
  CHECK(png_color_type(art4_png) == 3);
  CHECK(has_chunk(art4_png, "tRNS"));
  const Image back4 = io::decode_image(art4_png, "art4");
  REQUIRE(back4.channels == 4);
  CHECK(std::abs(back4.at(art.width - 1, 5, 3) - 128.0f / 255.0f) < 1.5f / 255.0f);
  CHECK(back4.at(0, 5, 3) == 1.0f);
  // At most 256 colours: the palette is exact.
  Image few = art;
  for (float& v : few.pixels) v = std::round(v * 5.0f) / 5.0f;  // 6 levels a channel: 216 colours
  const auto few_png = io::encode_image(few, faithful);
  CHECK(png_color_type(few_png) == 3);
  CHECK(rms_levels(few, io::decode_image(few_png, "few")) < 1e-3);  // texel for texel (float rounding aside)
  // Smooth colour would lose more than half a level: written as it is, texel for texel.
  Image smooth = smooth_image(96, 80, 3);
  for (float& v : smooth.pixels) v = std::round(v * 255.0f) / 255.0f;
  const auto smooth_png = io::encode_image(smooth, faithful);
  CHECK(png_color_type(smooth_png) == 2);
  CHECK(rms_levels(smooth, io::decode_image(smooth_png, "smooth")) < 1e-3);
  // Which inputs ask for it: 8-bit RGB and RGBA PNGs; not palettes (a palette always),
  // grey, 16-bit or JPEG.
  CHECK(io::encode_settings_of(art_rgb).palette_when_faithful);
  CHECK_FALSE(io::encode_settings_of(art_png).palette_when_faithful);
  CHECK(io::encode_settings_of(art_png).palette);
  CHECK(io::describe_encoded(art_png) == "png (8-bit palette)");
  CHECK(io::describe_encoded(art_rgb) == "png");
  CHECK(io::describe(io::encode_settings_of(art_rgb)) == "png (8-bit palette where faithful)");
  Image grey = smooth_image(32, 32, 1);
  CHECK_FALSE(io::encode_settings_of(io::encode_image(grey, "png")).palette_when_faithful);
  Image deep = smooth_image(32, 32, 3);
  deep.bits = 16;
  CHECK_FALSE(io::encode_settings_of(io::encode_image(deep, "png")).palette_when_faithful);
  CHECK_FALSE(io::encode_settings_of(io::encode_image(smooth, "jpeg")).palette_when_faithful);
}

TEST_CASE("PNG opaque alpha: an alpha channel whose every texel is opaque is not written", "[io][encode]") {
  for (uint32_t bits : {8u, 16u}) {
    Image rgba = smooth_image(40, 30, 4), ga = smooth_image(40, 30, 2);
    rgba.bits = ga.bits = bits;
    const auto opaque_rgba = io::encode_image(rgba, "png"), opaque_ga = io::encode_image(ga, "png");
    CHECK(png_color_type(opaque_rgba) == 2);
    CHECK(png_color_type(opaque_ga) == 0);
    const Image back = io::decode_image(opaque_rgba, "opaque");
    CHECK(back.channels == 3);
    CHECK(back.bits == bits);
    CHECK(mean_difference(rgba, back, 3) < 1e-6);  // lossless
    // One translucent texel: the alpha channel stays, exactly.
    rgba.at(7, 9, 3) = 0.5f;
    const auto kept = io::encode_image(rgba, "png");
    CHECK(png_color_type(kept) == 6);
    const Image back4 = io::decode_image(kept, "translucent");
    REQUIRE(back4.channels == 4);
    CHECK(std::abs(back4.at(7, 9, 3) - 0.5f) < (bits == 16 ? 1e-4f : 0.003f));
    CHECK(back4.at(8, 9, 3) == 1.0f);
  }
}

TEST_CASE("PNG at the best filter, deflated by libdeflate: no larger than OpenImageIO's default writer", "[io][encode]") {
  const Image img = smooth_image(128, 128, 3);
  const auto ours = io::encode_image(img, "png"), theirs = oiio_write(img, "memory.png", "");
  CHECK(ours.size() <= theirs.size());
  CHECK(mean_difference(img, io::decode_image(ours, "ours"), 3) < 1e-6);
}

TEST_CASE("PNG drafts decode to the texels of the final encode, RGB and palette, and cost more bytes", "[io][encode]") {
  // reparam scores its candidates from drafts and writes the kept one encoded for good:
  // what was scored must be what is written, texel for texel (the palette too).
  for (bool palette : {false, true}) {
    INFO("palette " << palette);
    const Image img = smooth_image(160, 96, 4);
    io::EncodeSettings final_settings;
    final_settings.palette = palette;
    io::EncodeSettings draft = final_settings;
    draft.draft = true;
    const auto a = io::encode_image(img, final_settings), b = io::encode_image(img, draft);
    CHECK(png_color_type(a) == png_color_type(b));
    const Image da = io::decode_image(a, "final"), db = io::decode_image(b, "draft");
    REQUIRE(da.pixels.size() == db.pixels.size());
    CHECK(da.pixels == db.pixels);
    CHECK(b.size() > a.size());  // the strongest of three passes against one fast one
  }
}

TEST_CASE("PNG palette on Duck's paletted texture: kept paletted and lossless, near the input's size, below RGB", "[io][encode][shared]") {
  auto shared = test::shared_dir();
  if (!shared) UVPRESS_SKIP("../shared is absent");
  const auto bytes = io::read_file((*shared / "assets/Duck/glTF/DuckCM.png").string());
  const io::EncodeSettings settings = io::encode_settings_of(bytes);
  CHECK(settings.format == "png");
  CHECK(settings.palette);
  const Image img = io::decode_image(bytes, "DuckCM.png");
  const auto again = io::encode_image(img, settings);
  CHECK(png_color_type(again) == 3);
  const auto rgb = io::encode_image(img, "png");
  INFO("input " << bytes.size() << " bytes, re-encoded " << again.size() << ", as RGB " << rgb.size());
  // The input was written by a stronger deflater than zlib (measured: 16,302 bytes; zlib 9
  // at libpng's best filter: 17,840; libdeflate 12 at it: 16,493). Within 2 % of it, and
  // below RGB; drawn from the input's own palette, texel for texel the input.
  CHECK(settings.palette_colours.size() == 54);
  CHECK(double(again.size()) <= 1.02 * double(bytes.size()));
  CHECK(again.size() < rgb.size());
  CHECK(io::decode_image(again, "again").pixels == img.pixels);
}

TEST_CASE("JPEG quality is estimated from the quantization tables of files written at 50, 75 and 90 (within 2)",
          "[io][encode]") {
  const Image img = smooth_image(64, 64, 3);
  for (int q : {50, 75, 90}) {
    INFO("quality " << q);
    // Another writer (OpenImageIO) at a known quality.
    const auto theirs = oiio_write(img, "memory.jpg", "jpeg:" + std::to_string(q));
    const io::JpegHeader h = io::read_jpeg_header(theirs.data(), theirs.size());
    REQUIRE(h.valid);
    CHECK(std::abs(h.quality - q) <= 2);
    const io::EncodeSettings s = io::encode_settings_of(theirs);
    CHECK(s.format == "jpeg");
    CHECK(std::abs(s.jpeg_quality - q) <= 2);
    // uvpress's own encoder at that quality reads back the same.
    io::JpegOptions o;
    o.quality = q;
    const auto ours = io::encode_jpeg(img, o);
    CHECK(io::read_jpeg_header(ours.data(), ours.size()).quality == q);
  }
  // A table that is no libjpeg scale of the standard one still gets the nearest quality.
  std::array<uint16_t, 64> flat{};
  flat.fill(8);
  const int nearest = io::estimate_jpeg_quality(flat, nullptr);
  CHECK(nearest > 50);
  CHECK(nearest < 100);
}

TEST_CASE("JPEG subsampling and progressive mode are read from the input and written the same", "[io][encode]") {
  const Image img = smooth_image(64, 48, 3);
  struct Case {
    int h, v;
    bool progressive;
  };
  for (const Case& c : {Case{2, 2, false}, Case{2, 1, true}, Case{1, 1, false}, Case{1, 1, true}}) {
    INFO(c.h << "x" << c.v << (c.progressive ? " progressive" : ""));
    io::JpegOptions o;
    o.quality = 83, o.h_sampling = c.h, o.v_sampling = c.v, o.progressive = c.progressive;
    const auto bytes = io::encode_jpeg(img, o);
    const io::EncodeSettings s = io::encode_settings_of(bytes);
    CHECK(s.jpeg_quality == 83);
    CHECK(s.jpeg_h_sampling == c.h);
    CHECK(s.jpeg_v_sampling == c.v);
    CHECK(s.progressive == c.progressive);
    // Re-encoding with the settings read back gives a file with the same settings.
    const auto again = io::encode_image(io::decode_image(bytes, "jpeg"), s);
    const io::JpegHeader h = io::read_jpeg_header(again.data(), again.size());
    CHECK(h.quality == 83);
    CHECK(h.h_sampling == c.h);
    CHECK(h.v_sampling == c.v);
    CHECK(h.progressive == c.progressive);
    CHECK(mean_difference(img, io::decode_image(again, "again"), 3) < 0.06);  // busy chroma at 4:2:0
  }
  // Truncated or foreign bytes: no header, no read past the end.
  const auto bytes = io::encode_jpeg(img, {});
  for (size_t n : {size_t(0), size_t(3), size_t(20), size_t(100)}) CHECK_FALSE(io::read_jpeg_header(bytes.data(), n).valid);
}

TEST_CASE("PNG palette importance: the texels that matter get the palette's colours first", "[io][encode][issue18]") {
  // Left half flat art with anti-aliased borders (a chart), right half noise (a gutter that
  // only coarse mip levels read): fitted alike, the noise takes entries from the art.
  const Image art = flat_art(128, 96, 12);
  const uint32_t W = 2 * art.width, H = art.height;
  std::vector<uint8_t> rgba(size_t(W) * H * 4), importance(size_t(W) * H);
  std::mt19937 rng(7);
  for (uint32_t y = 0; y < H; ++y)
    for (uint32_t x = 0; x < W; ++x) {
      uint8_t* p = &rgba[(size_t(y) * W + x) * 4];
      for (uint32_t c = 0; c < 3; ++c)
        p[c] = x < art.width ? uint8_t(std::lround(art.at(x, y, c) * 255.0f)) : uint8_t(rng() & 255);
      p[3] = 255;
      importance[size_t(y) * W + x] = x < art.width ? 255 : 16;
    }
  auto art_rms = [&](const io::PaletteImage& q) {
    double sum = 0;
    for (uint32_t y = 0; y < H; ++y)
      for (uint32_t x = 0; x < art.width; ++x) {
        const size_t i = size_t(y) * W + x;
        for (int c = 0; c < 3; ++c) sum += std::pow(double(q.palette[q.indices[i]][size_t(c)]) - rgba[i * 4 + size_t(c)], 2);
      }
    return std::sqrt(sum / (double(art.width) * H * 3));
  };
  const double alike = art_rms(io::quantize_palette(rgba.data(), W, H, 0.0f));
  const double weighted = art_rms(io::quantize_palette(rgba.data(), W, H, 0.0f, {}, &importance));
  INFO("the art's RMS error in 8-bit levels: fitted alike " << alike << ", weighted " << weighted);
  CHECK(weighted < 0.75 * alike);  // measured 0.90 against 1.47 levels
  // Through the encoder: the weights reach the palette and the faithful test. Now the left
  // half art of at most 216 colours, the right half a gentle gradient (more colours than a
  // palette holds): fitted alike the image loses 1.3 levels and is written as it is;
  // weighted (the gradient 1 in 255) the art keeps its colours, the gradient's error counts
  // for little, and the image is a palette.
  const Image smooth = smooth_image(art.width, H, 3);
  Image art2 = art;  // 6 levels a channel: at most 216 colours, which a palette holds exactly
  for (float& v : art2.pixels) v = std::round(v * 5.0f) / 5.0f;
  Image img;
  img.width = W, img.height = H, img.channels = 3;
  for (uint32_t y = 0; y < H; ++y)
    for (uint32_t x = 0; x < W; ++x)
      for (uint32_t c = 0; c < 3; ++c)
        img.pixels.push_back(std::round(255.0f * (x < art.width ? art2.at(x, y, c) : 0.4f + 0.2f * smooth.at(x - art.width, y, c))) / 255.0f);
  io::EncodeSettings s;
  s.palette_when_faithful = true;
  const auto alike_png = io::encode_image(img, s);
  s.importance = importance;
  for (uint32_t y = 0; y < H; ++y) std::fill_n(&s.importance[size_t(y) * W + art.width], art.width, uint8_t(1));
  const auto weighted_png = io::encode_image(img, s);
  auto half_rms = [&](const std::vector<uint8_t>& png, uint32_t x0) {
    const Image back = io::decode_image(png, "half");
    double sum = 0;
    for (uint32_t y = 0; y < H; ++y)
      for (uint32_t x = x0; x < x0 + art.width; ++x)
        for (uint32_t c = 0; c < 3; ++c) sum += std::pow(255.0 * (back.at(x, y, c) - img.at(x, y, c)), 2);
    return std::sqrt(sum / (double(art.width) * H * 3));
  };
  INFO("colour types alike " << png_color_type(alike_png) << ", weighted " << png_color_type(weighted_png) << "; weighted: art RMS "
                              << half_rms(weighted_png, 0) << ", gradient RMS " << half_rms(weighted_png, art.width));
  CHECK(png_color_type(alike_png) == 2);
  CHECK(png_color_type(weighted_png) == 3);
  CHECK(half_rms(weighted_png, 0) <= io::kFaithfulPaletteRms);
}
