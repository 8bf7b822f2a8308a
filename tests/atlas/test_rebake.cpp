#include <catch2/catch.hpp>

#include "atlas/rebake.h"
#include "support.h"

#include <omp.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <vector>

using namespace uvpress;
using atlas::RebakeMesh;
using atlas::RebakeOptions;
using atlas::RebakeRole;

namespace {

float hash01(uint32_t x, uint32_t y, uint32_t c) {
  uint32_t h = x * 73856093u ^ y * 19349663u ^ c * 83492791u;
  h ^= h >> 13, h *= 0x5bd1e995u, h ^= h >> 15;
  return float(h & 0xffff) / 65535.0f;
}

Image noise_image(uint32_t w, uint32_t h, uint32_t channels, float alpha_min = 1.0f) {
  Image im;
  im.width = w, im.height = h, im.channels = channels;
  im.pixels.resize(size_t(w) * h * channels);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x)
      for (uint32_t c = 0; c < channels; ++c) {
        float v = std::round(hash01(x, y, c) * 255.0f) / 255.0f;  // 8-bit values
        if ((channels == 4 && c == 3) || (channels == 2 && c == 1)) v = alpha_min + (1 - alpha_min) * v;
        im.at(x, y, c) = v;
      }
  return im;
}

// A quad as two triangles, with old and new UV corners (counter-clockwise in the y-down
// image: top-left, top-right, bottom-right, bottom-left).
struct Quad {
  std::vector<uint32_t> idx{0, 1, 2, 0, 2, 3};
  std::vector<float> old_uv, new_uv;
  RebakeMesh mesh() const { return {idx.data(), idx.size(), old_uv.data(), new_uv.data(), 4}; }
};

// Texel-rectangle corners -> UVs.
std::vector<float> rect_uv(double x0, double y0, double x1, double y1, double W, double H) {
  return {float(x0 / W), float(y0 / H), float(x1 / W), float(y0 / H),
          float(x1 / W), float(y1 / H), float(x0 / W), float(y1 / H)};
}

// The same four corners, rotated by R1 (x, y) -> (-y, x) and translated by (tx, ty), in texels.
std::vector<float> rotated_uv(double x0, double y0, double x1, double y1, double tx, double ty, double W, double H) {
  const double c[4][2] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  std::vector<float> uv;
  for (auto& p : c) {
    uv.push_back(float((-p[1] + tx) / W));
    uv.push_back(float((p[0] + ty) / H));
  }
  return uv;
}

}  // namespace

TEST_CASE("rebake: identity reproduces the source, alpha kept", "[atlas]") {
  for (RebakeRole role : {RebakeRole::Color, RebakeRole::Data}) {
    const Image src = noise_image(64, 48, 4, 0.2f);
    Quad q;
    q.old_uv = q.new_uv = rect_uv(6, 5, 58, 43, 64, 48);
    RebakeOptions o;
    o.width = 64, o.height = 48, o.role = role;
    atlas::RebakeStats stats;
    const Image out = atlas::rebake(src, {q.mesh()}, o, test::cpu_engine(), &stats);
    REQUIRE(out.width == 64);
    REQUIRE(out.channels == 4);
    CHECK(out.bits == src.bits);
    CHECK(stats.covered == size_t(52) * 38);
    // Inside the chart (every texel: its centre maps to a source texel centre): within
    // 1e-5 (sRGB decode/encode round trip and the premultiply/divide in float).
    float worst = 0, worst_alpha = 0;
    for (uint32_t y = 5; y < 43; ++y)
      for (uint32_t x = 6; x < 58; ++x) {
        for (uint32_t c = 0; c < 3; ++c) worst = std::max(worst, std::abs(out.at(x, y, c) - src.at(x, y, c)));
        worst_alpha = std::max(worst_alpha, std::abs(out.at(x, y, 3) - src.at(x, y, 3)));
      }
    CHECK(worst < 1e-5f);
    CHECK(worst_alpha < 1e-6f);
  }
}

TEST_CASE("rebake: a translated or quarter-turned chart moves its pixels", "[atlas]") {
  const Image src = noise_image(32, 32, 3);
  RebakeOptions o;
  o.width = 32, o.height = 32, o.role = RebakeRole::Data;
  SECTION("translation") {
    Quad q;
    q.old_uv = rect_uv(4, 4, 20, 20, 32, 32);
    q.new_uv = rect_uv(13, 9, 29, 25, 32, 32);
    const Image out = atlas::rebake(src, {q.mesh()}, o, test::cpu_engine());
    float worst = 0;
    for (int j = 4; j < 20; ++j)
      for (int i = 4; i < 20; ++i)
        for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(out.at(i + 9, j + 5, c) - src.at(i, j, c)));
    CHECK(worst < 1e-6f);
  }
  SECTION("quarter turn") {
    // new = R1 old + (28, 8): old texel (i, j) -> new texel (27 - j, i + 8).
    Quad q;
    q.old_uv = rect_uv(4, 4, 20, 20, 32, 32);
    q.new_uv = rotated_uv(4, 4, 20, 20, 28, 8, 32, 32);
    const Image out = atlas::rebake(src, {q.mesh()}, o, test::cpu_engine());
    float worst = 0;
    for (int j = 4; j < 20; ++j)
      for (int i = 4; i < 20; ++i)
        for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(out.at(27 - j, i + 8, c) - src.at(i, j, c)));
    CHECK(worst < 1e-6f);
  }
}

TEST_CASE("rebake: 2x and 4x downscale of a fine checker is the mean, not aliasing", "[atlas]") {
  Image src;
  src.width = src.height = 64, src.channels = 3;
  src.pixels.resize(64 * 64 * 3);
  for (uint32_t y = 0; y < 64; ++y)
    for (uint32_t x = 0; x < 64; ++x)
      for (uint32_t c = 0; c < 3; ++c) src.at(x, y, c) = float((x + y) % 2);
  Quad q;
  q.old_uv = q.new_uv = rect_uv(0, 0, 1, 1, 1, 1);
  for (uint32_t size : {32u, 16u}) {
    RebakeOptions o;
    o.width = o.height = size;
    o.role = RebakeRole::Data;
    const Image grey = atlas::rebake(src, {q.mesh()}, o, test::cpu_engine());
    o.role = RebakeRole::Color;  // averaged in linear light, stored sRGB-encoded
    const Image colour = atlas::rebake(src, {q.mesh()}, o, test::cpu_engine());
    float worst_data = 0, worst_colour = 0;
    const float srgb_half = atlas::linear_to_srgb(0.5f);
    for (size_t i = 0; i < grey.pixels.size(); ++i) {
      worst_data = std::max(worst_data, std::abs(grey.pixels[i] - 0.5f));
      worst_colour = std::max(worst_colour, std::abs(colour.pixels[i] - srgb_half));
    }
    CHECK(worst_data < 1e-5f);
    CHECK(worst_colour < 1e-4f);
    CHECK(srgb_half == Approx(0.7354).epsilon(1e-3));
  }
}

TEST_CASE("rebake: gutters take the nearest chart's colour, never the background", "[atlas]") {
  // Source: black, with a red square and a green square.
  Image src;
  src.width = src.height = 32, src.channels = 4;
  src.pixels.assign(32 * 32 * 4, 0.0f);
  for (uint32_t y = 0; y < 32; ++y)
    for (uint32_t x = 0; x < 32; ++x) {
      src.at(x, y, 3) = 1;
      if (x >= 2 && x < 14 && y >= 2 && y < 14) src.at(x, y, 0) = 1;
      if (x >= 18 && x < 30 && y >= 2 && y < 14) src.at(x, y, 1) = 1;
    }
  // Old: the inner 8x8 of each square. New: two charts at fractional texel positions in a
  // 32 x 24 atlas, 5 texels apart.
  Quad a, b;
  a.old_uv = rect_uv(4, 4, 12, 12, 32, 32);
  a.new_uv = rect_uv(3.3, 4.6, 11.4, 12.5, 32, 24);
  b.old_uv = rect_uv(20, 4, 28, 12, 32, 32);
  b.new_uv = rect_uv(16.4, 4.6, 24.7, 12.5, 32, 24);
  RebakeOptions o;
  o.width = 32, o.height = 24;
  atlas::RebakeStats stats;
  const Image out = atlas::rebake(src, {a.mesh(), b.mesh()}, o, test::cpu_engine(), &stats);
  CHECK(stats.covered == size_t(9 * 9 + 9 * 9));  // conservative: partly covered texels count
  auto is = [&](int x, int y, float r, float g) {
    return std::abs(out.at(x, y, 0) - r) < 1e-5f && std::abs(out.at(x, y, 1) - g) < 1e-5f &&
           std::abs(out.at(x, y, 2)) < 1e-5f && std::abs(out.at(x, y, 3) - 1) < 1e-5f;
  };
  int bad = 0;
  for (int y = 0; y < 24; ++y)
    for (int x = 0; x < 32; ++x) {
      // Every texel is pure red or pure green: no black, no blend.
      if (!is(x, y, 1, 0) && !is(x, y, 0, 1)) ++bad;
    }
  CHECK(bad == 0);
  // Gutter texels: the nearest chart's colour.
  CHECK(is(12, 8, 1, 0));   // just right of the red chart (its last texel is 11)
  CHECK(is(13, 8, 1, 0));
  CHECK(is(15, 8, 0, 1));   // nearer green (starts at 16)
  CHECK(is(0, 0, 1, 0));    // the corner
  CHECK(is(31, 23, 0, 1));
  CHECK(is(7, 22, 1, 0));   // below red
  CHECK(is(20, 22, 0, 1));  // below green
  // Coverage mask: the partly covered texel 11 is covered, 12 is gutter.
  REQUIRE(stats.coverage.size() == 32 * 24);
  CHECK(stats.coverage[8 * 32 + 11] == 1);
  CHECK(stats.coverage[8 * 32 + 12] == 0);
}

TEST_CASE("rebake: a normal map under a quarter turn has its xy rotated", "[atlas]") {
  // Tangent-space normal tilted toward +u (image right): n = (0.6, 0, 0.8).
  Image src;
  src.width = src.height = 32, src.channels = 3;
  src.pixels.resize(32 * 32 * 3);
  for (size_t i = 0; i < 32 * 32; ++i) {
    src.pixels[3 * i] = 0.8f, src.pixels[3 * i + 1] = 0.5f, src.pixels[3 * i + 2] = 0.9f;
  }
  RebakeOptions o;
  o.width = 32, o.height = 32, o.role = RebakeRole::Normal;
  auto stored = [](double n) { return float((n + 1) / 2); };
  SECTION("translation keeps it") {
    Quad q;
    q.old_uv = rect_uv(4, 4, 20, 20, 32, 32);
    q.new_uv = rect_uv(10, 10, 26, 26, 32, 32);
    const Image out = atlas::rebake(src, {q.mesh()}, o, test::cpu_engine());
    CHECK(out.at(15, 15, 0) == Approx(0.8f).margin(1e-5));
    CHECK(out.at(15, 15, 1) == Approx(0.5f).margin(1e-5));
    CHECK(out.at(15, 15, 2) == Approx(0.9f).margin(1e-5));
  }
  SECTION("quarter turn: old right becomes new down, i.e. -y in the +Y-up normal frame") {
    Quad q;
    q.old_uv = rect_uv(4, 4, 20, 20, 32, 32);
    q.new_uv = rotated_uv(4, 4, 20, 20, 28, 8, 32, 32);
    const Image out = atlas::rebake(src, {q.mesh()}, o, test::cpu_engine());
    for (auto [x, y] : {std::pair{15, 18}, std::pair{9, 13}, std::pair{26, 26}}) {
      CHECK(out.at(x, y, 0) == Approx(stored(0.0)).margin(1e-5));
      CHECK(out.at(x, y, 1) == Approx(stored(-0.6)).margin(1e-5));
      CHECK(out.at(x, y, 2) == Approx(stored(0.8)).margin(1e-5));
    }
  }
  SECTION("the opposite quarter turn gives +y; a 2x shrink keeps it unit") {
    // new = R1^-1 old + t: (x, y) -> (y, -x) + (8, 28), scaled by 1/2 about the origin.
    Quad q;
    q.old_uv = rect_uv(4, 4, 20, 20, 32, 32);
    const double c[4][2] = {{4, 4}, {20, 4}, {20, 20}, {4, 20}};
    for (auto& p : c) {
      q.new_uv.push_back(float((0.5 * p[1] + 4) / 32));
      q.new_uv.push_back(float((-0.5 * p[0] + 14) / 32));
    }
    const Image out = atlas::rebake(src, {q.mesh()}, o, test::cpu_engine());
    CHECK(out.at(10, 8, 0) == Approx(stored(0.0)).margin(1e-5));
    CHECK(out.at(10, 8, 1) == Approx(stored(0.6)).margin(1e-5));
    CHECK(out.at(10, 8, 2) == Approx(stored(0.8)).margin(1e-5));
  }
}

TEST_CASE("rebake: transparent texels do not tint (premultiplied), alpha is averaged", "[atlas]") {
  // Columns alternate opaque red and fully transparent blue; a 2x reduction.
  Image src;
  src.width = src.height = 16, src.channels = 4;
  src.pixels.resize(16 * 16 * 4);
  for (uint32_t y = 0; y < 16; ++y)
    for (uint32_t x = 0; x < 16; ++x) {
      const bool red = x % 2 == 0;
      src.at(x, y, 0) = red ? 1.f : 0.f;
      src.at(x, y, 1) = 0;
      src.at(x, y, 2) = red ? 0.f : 1.f;
      src.at(x, y, 3) = red ? 1.f : 0.f;
    }
  Quad q;
  q.old_uv = q.new_uv = rect_uv(0, 0, 1, 1, 1, 1);
  RebakeOptions o;
  o.width = o.height = 8;
  const Image out = atlas::rebake(src, {q.mesh()}, o, test::cpu_engine());
  CHECK(out.at(3, 3, 0) == Approx(1.0f).margin(1e-5));
  CHECK(out.at(3, 3, 2) == Approx(0.0f).margin(1e-5));
  CHECK(out.at(3, 3, 3) == Approx(0.5f).margin(1e-5));
}

TEST_CASE("rebake: same result on 1 and 2 threads", "[atlas]") {
  const Image src = noise_image(64, 64, 4, 0.5f);
  // A 6x6 grid of quads, new UVs a rotated, shrunk copy.
  std::vector<uint32_t> idx;
  std::vector<float> ouv, nuv;
  for (int j = 0; j <= 6; ++j)
    for (int i = 0; i <= 6; ++i) {
      const double u = 0.05 + 0.9 * i / 6, v = 0.05 + 0.9 * j / 6;
      ouv.push_back(float(u)), ouv.push_back(float(v));
      nuv.push_back(float(0.1 + 0.6 * v + 0.05 * u)), nuv.push_back(float(0.9 - 0.7 * u + 0.03 * v));
    }
  for (uint32_t j = 0; j < 6; ++j)
    for (uint32_t i = 0; i < 6; ++i) {
      const uint32_t a = j * 7 + i;
      idx.insert(idx.end(), {a, a + 1, a + 8, a, a + 8, a + 7});
    }
  RebakeMesh m{idx.data(), idx.size(), ouv.data(), nuv.data(), ouv.size() / 2};
  RebakeOptions o;
  o.width = 40, o.height = 40;
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const Image a = atlas::rebake(src, {m}, o, test::cpu_engine());
  omp_set_num_threads(2);
  const Image b = atlas::rebake(src, {m}, o, test::cpu_engine());
  omp_set_num_threads(threads);
  CHECK(a.pixels == b.pixels);
}

TEST_CASE("rebake: 2048^2 RGBA timing", "[.][bench][rebake-bench]") {
  const Image src = noise_image(2048, 2048, 4, 0.5f);
  std::vector<uint32_t> idx;
  std::vector<float> ouv, nuv;
  const int n = 64;  // 2 * 64^2 = 8192 triangles, new UVs a rotated copy
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double u = double(i) / n, v = double(j) / n;
      ouv.push_back(float(u)), ouv.push_back(float(v));
      nuv.push_back(float(1 - v)), nuv.push_back(float(u));
    }
  for (uint32_t j = 0; j < uint32_t(n); ++j)
    for (uint32_t i = 0; i < uint32_t(n); ++i) {
      const uint32_t a = j * (n + 1) + i;
      idx.insert(idx.end(), {a, a + 1, a + n + 2, a, a + n + 2, a + n + 1});
    }
  RebakeMesh m{idx.data(), idx.size(), ouv.data(), nuv.data(), ouv.size() / 2};
  RebakeOptions o;
  o.width = o.height = 2048;
  for (RebakeRole role : {RebakeRole::Color, RebakeRole::Data}) {
    o.role = role;
    const auto t0 = std::chrono::steady_clock::now();
    const Image out = atlas::rebake(src, {m}, o, test::cpu_engine());
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    WARN("rebake 2048^2 RGBA " << (role == RebakeRole::Color ? "colour" : "data") << ": " << s << " s on "
                               << omp_get_max_threads() << " threads");
    CHECK(out.width == 2048);
  }
  o.width = o.height = 1024;  // 2x downscale: 4 samples per texel
  o.role = RebakeRole::Color;
  const auto t0 = std::chrono::steady_clock::now();
  atlas::rebake(src, {m}, o, test::cpu_engine());
  WARN("rebake 2048^2 -> 1024^2 colour: "
       << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s");
}
