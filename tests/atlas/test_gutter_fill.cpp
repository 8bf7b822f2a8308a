#include <catch2/catch.hpp>

#include "atlas/gutter_fill.h"
#include "atlas/rebake.h"
#include "io/image_io.h"
#include "support.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

using namespace uvpress;

namespace {

// Two triangles covering [x0,x1] x [y0,y1] (texels of a w x h image) as glTF UVs.
std::vector<float> rect_uv(double x0, double y0, double x1, double y1, double w, double h) {
  return {float(x0 / w), float(y0 / h), float(x1 / w), float(y0 / h), float(x1 / w), float(y1 / h), float(x0 / w), float(y1 / h)};
}

// The mip chain a viewer builds (glGenerateMipmap): 2x2 box averages of colour in linear
// light, level k of a 2^n-sided image being (w >> k) x (h >> k). Returns level k's linear
// RGB per texel.
std::vector<float> mip_level(const Image& img, int k) {
  const int w = int(img.width) >> k, h = int(img.height) >> k, s = 1 << k;
  std::vector<float> out(size_t(w) * h * 3, 0.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        double sum = 0;
        for (int v = 0; v < s; ++v)
          for (int u = 0; u < s; ++u) sum += atlas::srgb_to_linear(img.at(uint32_t(x * s + u), uint32_t(y * s + v), uint32_t(c)));
        out[(size_t(y) * w + x) * 3 + c] = float(sum / (s * s));
      }
  return out;
}

// At level k, the texels whose block holds texels of a chart: 1 red's, 2 green's, 3 both.
std::vector<int> footprint_at(const std::vector<uint8_t>& coverage, int W, int H, int split_x, int k) {
  const int w = W >> k, h = H >> k, s = 1 << k;
  std::vector<int> holds(size_t(w) * h, 0);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      if (coverage[size_t(y) * W + x]) holds[size_t(y / s) * w + x / s] |= x < split_x ? 1 : 2;
  return holds;
}

// Level-k texels of one chart's footprint that show the other chart's colour (red and green
// are kept in separate channels, so any trace of the other is a leak).
int leaks(const Image& img, const std::vector<uint8_t>& coverage, int split_x, int k) {
  const std::vector<float> level = mip_level(img, k);
  const std::vector<int> holds = footprint_at(coverage, int(img.width), int(img.height), split_x, k);
  int bad = 0;
  for (size_t i = 0; i < holds.size(); ++i) {
    if (holds[i] == 1 && level[3 * i + 1] > 1e-6f) ++bad;
    if (holds[i] == 2 && level[3 * i + 0] > 1e-6f) ++bad;
  }
  return bad;
}

}  // namespace

TEST_CASE("gutter fill: each chart's colour reaches every mip level down to the gutter's width", "[atlas]") {
  // Source: a red chart (R varies, G = B = 0) beside a green one (G varies). New layout: the
  // two charts 8 texels apart in a 64 x 32 atlas, the midline between them (x = 24.5) not
  // on a level-3 block boundary, so a nearest-chart fill puts red into the level-3 block
  // of green's left edge (texels 24..31).
  Image src;
  src.width = src.height = 32, src.channels = 3;
  src.pixels.assign(32 * 32 * 3, 0.0f);
  for (uint32_t y = 0; y < 32; ++y)
    for (uint32_t x = 0; x < 32; ++x) src.at(x, y, x < 16 ? 0 : 1) = 0.3f + 0.02f * float((x * 7 + y * 3) % 32);
  const std::vector<uint32_t> quad = {0, 1, 2, 0, 2, 3};
  const std::vector<float> red_old = rect_uv(2, 2, 14, 30, 32, 32), red_new = rect_uv(2.3, 3.2, 20.6, 27.7, 64, 32);
  const std::vector<float> green_old = rect_uv(18, 2, 30, 30, 32, 32), green_new = rect_uv(29.4, 3.2, 61.2, 27.7, 64, 32);
  const std::vector<atlas::RebakeMesh> meshes = {{quad.data(), 6, red_old.data(), red_new.data(), 4},
                                                 {quad.data(), 6, green_old.data(), green_new.data(), 4}};
  atlas::RebakeOptions o;
  o.width = 64, o.height = 32;
  atlas::RebakeStats stats;
  const Image baked = atlas::rebake(src, meshes, o, test::cpu_engine(), &stats);
  const std::vector<uint8_t>& cov = stats.coverage;
  // The layout: footprints at texels 2..20 and 29..61, so 8 empty texels between them.
  REQUIRE(cov[10 * 64 + 20] == 1);
  REQUIRE(cov[10 * 64 + 21] == 0);
  REQUIRE(cov[10 * 64 + 28] == 0);
  REQUIRE(cov[10 * 64 + 29] == 1);
  const int split = 25;
  // No level-k block (k <= 3) holds both charts: the gutter is 8 = 2^3.
  for (int k = 0; k <= 3; ++k)
    for (int h : footprint_at(cov, 64, 32, split, k)) REQUIRE(h != 3);

  // rebake's fill: at levels 0..3 every texel of a chart's footprint is that chart's alone.
  for (int k = 0; k <= 3; ++k) {
    INFO("level " << k);
    CHECK(leaks(baked, cov, split, k) == 0);
  }
  // Covered texels are the bake's; gutter texels next to a chart carry its edge colour.
  CHECK(baked.at(21, 10, 1) == 0.0f);
  CHECK(baked.at(21, 10, 0) == Approx(baked.at(20, 10, 0)));
  CHECK(baked.at(28, 10, 0) == 0.0f);
  CHECK(baked.at(28, 10, 1) == Approx(baked.at(29, 10, 1)));

  // The nearest-chart fill alone (a ring as wide as the image) leaks at level 3: the
  // level-3 block 24..31 holds green's edge and red's share of the gutter (24).
  atlas::RebakeOptions bare = o;
  bare.fill_gutter = false;
  Image nearest = atlas::rebake(src, meshes, bare, test::cpu_engine());
  atlas::fill_gutter(nearest, cov, true, 1000);
  CHECK(leaks(nearest, cov, split, 2) == 0);
  CHECK(leaks(nearest, cov, split, 3) > 0);
}

TEST_CASE("gutter fill: a chart alone extends its mean through the whole chain", "[atlas]") {
  // One covered texel block in a 16 x 16 data image: every level's block that holds it
  // averages to the covered texels' own mean, so the top level is exactly that mean.
  Image img;
  img.width = img.height = 16, img.channels = 1;
  img.pixels.assign(256, 0.0f);
  std::vector<uint8_t> cov(256, 0);
  const float v[4] = {0.1f, 0.5f, 0.2f, 0.8f};
  for (int i = 0; i < 4; ++i) {
    const int x = 5 + i % 2, y = 9 + i / 2;
    img.at(uint32_t(x), uint32_t(y), 0) = v[i];
    cov[size_t(y) * 16 + x] = 1;
  }
  atlas::fill_gutter(img, cov, false, 0);
  double sum = 0;
  for (float p : img.pixels) sum += p;
  CHECK(sum / 256 == Approx((0.1 + 0.5 + 0.2 + 0.8) / 4).epsilon(1e-5));
  // Each 8 x 8 quadrant is a level-3 texel: the one holding the chart is its mean too.
  double q = 0;
  for (int y = 8; y < 16; ++y)
    for (int x = 0; x < 8; ++x) q += img.at(uint32_t(x), uint32_t(y), 0);
  CHECK(q / 64 == Approx(0.4).epsilon(1e-5));
}

TEST_CASE("gutter fill: the mip-safe gutter grows with the image's side", "[atlas]") {
  CHECK(atlas::mip_safe_gutter(128.0 * 128) == 4);  // the minimum
  CHECK(atlas::mip_safe_gutter(256.0 * 256) == 4);  // clean down to 64^2
  CHECK(atlas::mip_safe_gutter(362.0 * 362) == 8);  // Duck at half its texels: clean to 45^2
  CHECK(atlas::mip_safe_gutter(1024.0 * 512) == 16);
  CHECK(atlas::mip_safe_gutter(2048.0 * 2048) == 16);   // the cap
  CHECK(atlas::mip_safe_gutter(2048.0 * 2048, 64, 4, 64) == 32);
  CHECK(atlas::mip_safe_gutter(16384.0 * 16384, 64, 4, 64) == 64);
}

namespace {

// A W x H sRGB image whose charts hold a smooth gradient and whose gutter holds noise
// (8-bit values, as a decoded texture): a disc in the middle and a bar along the right edge,
// which a sampler that repeats reads across to the left edge.
struct NoisyAtlas {
  Image image;
  std::vector<uint8_t> footprint;
};
NoisyAtlas noisy_atlas(uint32_t W, uint32_t H) {
  NoisyAtlas a;
  a.image.width = W, a.image.height = H, a.image.channels = 3;
  a.image.pixels.resize(size_t(W) * H * 3);
  a.footprint.assign(size_t(W) * H, 0);
  uint32_t state = 12345;
  for (uint32_t y = 0; y < H; ++y)
    for (uint32_t x = 0; x < W; ++x) {
      const double dx = x + 0.5 - 44.0, dy = y + 0.5 - 52.0;
      const bool chart = dx * dx + dy * dy <= 20.0 * 20.0 || (x >= W - 6 && y >= 60 && y < 84);
      a.footprint[size_t(y) * W + x] = chart;
      for (uint32_t c = 0; c < 3; ++c) {
        state = state * 1664525u + 1013904223u;
        const uint32_t v = chart ? (x + 2 * y + 40 * c) % 256 : state >> 24;
        a.image.at(x, y, c) = float(v) / 255.0f;
      }
    }
  return a;
}

void round_to_8_bits(Image& img) {
  for (float& v : img.pixels) v = std::round(v * 255.0f) / 255.0f;
}

}  // namespace

TEST_CASE("coarsen gutter: every mip level reads near a chart what it read before, and the gutter's detail is gone",
          "[atlas][issue18]") {
  const uint32_t W = 128, H = 128;
  const NoisyAtlas a = noisy_atlas(W, H);
  Image flat = a.image;
  atlas::coarsen_gutter(flat, a.footprint, true, /*wrap_x=*/true, /*wrap_y=*/false, 64);
  round_to_8_bits(flat);  // as written

  // Chebyshev distance to the footprint, by brute force (x wrapping, y not).
  std::vector<int> d(size_t(W) * H, 1 << 20);
  for (uint32_t fy = 0; fy < H; ++fy)
    for (uint32_t fx = 0; fx < W; ++fx) {
      if (!a.footprint[size_t(fy) * W + fx]) continue;
      for (uint32_t y = 0; y < H; ++y)
        for (uint32_t x = 0; x < W; ++x) {
          const int ax = std::abs(int(x) - int(fx)), ddx = std::min(ax, int(W) - ax);
          int& t = d[size_t(y) * W + x];
          t = std::min(t, std::max(ddx, std::abs(int(y) - int(fy))));
        }
    }
  // Level 0: the footprint and its ring (bilinear taps) exactly as they were; farther out
  // the gutter is flat.
  size_t kept_changed = 0, gutter = 0, gutter_changed = 0;
  for (size_t i = 0; i < d.size(); ++i)
    for (uint32_t c = 0; c < 3; ++c) {
      const bool same = flat.pixels[i * 3 + c] == a.image.pixels[i * 3 + c];
      if (d[i] <= 1) kept_changed += !same;
      if (d[i] >= 2) gutter += 1, gutter_changed += !same;
    }
  CHECK(kept_changed == 0);
  CHECK(gutter_changed > gutter / 2);  // noise made flat (a texel that matched its mean by chance stays)
  // Levels 1..7 (the chain a viewer builds, tests' own box filter): every texel that a
  // bilinear tap from inside a chart can read (the level-k texel under a footprint texel and
  // its neighbours, wrapping in x) holds what it held, to 8-bit rounding. A block shifted
  // by one texel, or a texel flattened one level too coarse, moves these by ~0.1.
  for (int k = 1; k <= 7; ++k) {
    const auto before = mip_level(a.image, k), after = mip_level(flat, k);
    const int w = int(W) >> k, h = int(H) >> k;
    double worst = 0;
    for (uint32_t y = 0; y < H; ++y)
      for (uint32_t x = 0; x < W; ++x) {
        if (!a.footprint[size_t(y) * W + x]) continue;
        for (int v = int(y >> k) - 1; v <= int(y >> k) + 1; ++v)
          for (int u = int(x >> k) - 1; u <= int(x >> k) + 1; ++u) {
            if (v < 0 || v >= h) continue;
            const size_t t = (size_t(v) * w + size_t((u + w) % w)) * 3;
            for (int c = 0; c < 3; ++c) worst = std::max(worst, double(std::abs(after[t + c] - before[t + c])));
          }
      }
    INFO("level " << k);
    CHECK(worst < 0.006);
  }
  // Without the wrap, the bar's neighbours across the left edge are gutter like any other.
  Image clamped = a.image;
  atlas::coarsen_gutter(clamped, a.footprint, true, false, false, 64);
  CHECK(clamped.at(0, 70, 0) != a.image.at(0, 70, 0));
  CHECK(flat.at(0, 70, 0) == a.image.at(0, 70, 0));
  // What it is for: the noise gone, the file shrinks.
  const size_t bytes_before = io::encode_image(a.image, "png").size(), bytes_after = io::encode_image(flat, "png").size();
  INFO(bytes_before << " -> " << bytes_after);
  CHECK(bytes_after < bytes_before / 2);
}

TEST_CASE("coarsen gutter: blocks only as coarse as both sides divide", "[atlas][issue18]") {
  // An odd side: its chain's blocks drift against level 0, so nothing is flattened.
  NoisyAtlas odd = noisy_atlas(129, 128);
  Image img = odd.image;
  atlas::coarsen_gutter(img, odd.footprint, true);
  CHECK(img.pixels == odd.image.pixels);
  // 130 = 2 x 65: 2 x 2 blocks and no coarser. A texel 10 away from any chart takes its
  // 2 x 2 block's mean (of the block's texels as far out), not an 8 x 8 block's.
  NoisyAtlas even = noisy_atlas(130, 128);
  img = even.image;
  atlas::coarsen_gutter(img, even.footprint, false, false, false);
  const uint32_t x = 100, y = 10;  // far from the disc and the bar
  double mean = 0;
  for (uint32_t v = y; v < y + 2; ++v)
    for (uint32_t u = x; u < x + 2; ++u) mean += even.image.at(u, v, 0) / 4.0;
  CHECK(img.at(x, y, 0) == Approx(mean).epsilon(1e-6));
  CHECK(img.at(x + 1, y + 1, 0) == Approx(mean).epsilon(1e-6));
  // Nothing happens without a chart.
  std::vector<uint8_t> none(even.footprint.size(), 0);
  img = even.image;
  atlas::coarsen_gutter(img, none, true);
  CHECK(img.pixels == even.image.pixels);
}
