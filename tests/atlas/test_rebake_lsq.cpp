// The least-squares re-bake (host/atlas/rebake_lsq.h) against the area filter, measured
// independently of the solver's objective: the rendered result (the new image sampled
// bilinearly in linear light, double precision) at random surface points against the
// source sampled the same way at the points' old UVs.
#include <catch2/catch.hpp>

#include "atlas/rebake.h"
#include "atlas/dark_chart_on_white.h"
#include "atlas/rebake_lanczos.h"
#include "atlas/rebake_lsq.h"
#include "core/image.h"
#include "support.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

using namespace uvpress;
using atlas::RebakeMesh;
using atlas::RebakeOptions;
using atlas::RebakeRole;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A detailed texture: sinusoids up to ~0.4 cycles per texel in several directions plus
// per-texel noise, 8-bit values.
Image detailed_image(uint32_t w, uint32_t h, uint32_t channels) {
  Image im;
  im.width = w, im.height = h, im.channels = channels;
  im.pixels.resize(size_t(w) * h * channels);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> noise(-1, 1);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x)
      for (uint32_t c = 0; c < channels; ++c) {
        double v = 0.5 + 0.18 * std::sin(2 * kPi * (0.31 * x + 0.07 * y) + c) +
                   0.12 * std::sin(2 * kPi * (0.05 * x - 0.23 * y) + 2 * c) +
                   0.08 * std::sin(2 * kPi * (0.11 * x + 0.13 * y)) + 0.07 * noise(rng);
        if (channels == 4 && c == 3) v = 1.0;
        im.at(x, y, c) = float(std::round(std::clamp(v, 0.0, 1.0) * 255.0) / 255.0);
      }
  return im;
}

// A chart: an n x n grid of quads over the source texel square [x0, x0 + s]^2, its new UVs
// that square scaled by `scale` and rotated by `degrees` about the new image's centre.
struct Layout {
  std::vector<uint32_t> idx;
  std::vector<float> old_uv, new_uv;
  RebakeMesh mesh() const { return {idx.data(), idx.size(), old_uv.data(), new_uv.data(), old_uv.size() / 2}; }
};

Layout grid_layout(double x0, double s, int n, double SW, double SH, double degrees, double scale, double W, double H) {
  Layout L;
  const double c = std::cos(degrees * kPi / 180), sn = std::sin(degrees * kPi / 180);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double ox = x0 + s * i / n, oy = x0 + s * j / n;
      L.old_uv.push_back(float(ox / SW)), L.old_uv.push_back(float(oy / SH));
      const double dx = (ox - (x0 + s / 2)) * scale, dy = (oy - (x0 + s / 2)) * scale;
      L.new_uv.push_back(float((W / 2 + c * dx - sn * dy) / W));
      L.new_uv.push_back(float((H / 2 + sn * dx + c * dy) / H));
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t v = uint32_t(j * (n + 1) + i), w = uint32_t(n + 1);
      L.idx.insert(L.idx.end(), {v, v + 1, v + w + 1, v, v + w + 1, v + w});
    }
  return L;
}

// Bilinear sample in linear light (sRGB decoded per texel when colour), texel centres at
// integers + 0.5, clamped to the image.
double bilinear(const Image& im, double u, double v, uint32_t c, bool srgb) {
  const double x = u * im.width - 0.5, y = v * im.height - 0.5;
  const double fx = std::floor(x), fy = std::floor(y);
  const double ax = x - fx, ay = y - fy;
  auto at = [&](int i, int j) {
    i = std::clamp(i, 0, int(im.width) - 1), j = std::clamp(j, 0, int(im.height) - 1);
    const double s = im.at(uint32_t(i), uint32_t(j), c);
    return srgb ? double(atlas::srgb_to_linear(float(s))) : s;
  };
  const int i = int(fx), j = int(fy);
  return (1 - ay) * ((1 - ax) * at(i, j) + ax * at(i + 1, j)) + ay * ((1 - ax) * at(i, j + 1) + ax * at(i + 1, j + 1));
}

// RMS difference between the rendered new image and the rendered source over `count`
// area-uniform random points of the new-UV triangles (colour channels, linear light).
double surface_rms(const Image& source, const Image& baked, const Layout& L, bool srgb, int count = 200000) {
  std::vector<double> cum;
  double total = 0;
  for (size_t t = 0; t < L.idx.size(); t += 3) {
    const float* a = &L.new_uv[2 * L.idx[t]];
    const float* b = &L.new_uv[2 * L.idx[t + 1]];
    const float* c = &L.new_uv[2 * L.idx[t + 2]];
    total += std::abs((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
    cum.push_back(total);
  }
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(0, 1);
  const uint32_t channels = std::min<uint32_t>(source.channels, 3);
  double sum = 0;
  for (int s = 0; s < count; ++s) {
    const size_t t = size_t(std::lower_bound(cum.begin(), cum.end(), U(rng) * total) - cum.begin()) * 3;
    double r1 = U(rng), r2 = U(rng);
    if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
    const double w[3] = {1 - r1 - r2, r1, r2};
    double nu = 0, nv = 0, ou = 0, ov = 0;
    for (int k = 0; k < 3; ++k) {
      const uint32_t id = L.idx[std::min(t, L.idx.size() - 3) + size_t(k)];
      nu += w[k] * L.new_uv[2 * id], nv += w[k] * L.new_uv[2 * id + 1];
      ou += w[k] * L.old_uv[2 * id], ov += w[k] * L.old_uv[2 * id + 1];
    }
    for (uint32_t c = 0; c < channels; ++c) {
      const double d = bilinear(baked, nu, nv, c, srgb) - bilinear(source, ou, ov, c, srgb);
      sum += d * d;
    }
  }
  return std::sqrt(sum / (double(count) * channels));
}

struct Bakes {
  Image area, lsq;
  atlas::LsqBakeStats stats;
};

Bakes bake_both(const Image& src, const Layout& L, const RebakeOptions& o, const atlas::LsqBakeOptions& lsq = {}) {
  Bakes b;
  b.area = atlas::rebake(src, {L.mesh()}, o, test::cpu_engine());
  b.lsq = atlas::rebake_least_squares(src, {L.mesh()}, o, b.area, &b.stats, lsq);
  return b;
}

}  // namespace

TEST_CASE("rebake_lsq: a 30-degree rotation at the same density loses less than the area filter", "[atlas][lsq]") {
  const Image src = detailed_image(128, 128, 3);
  const Layout L = grid_layout(16, 96, 8, 128, 128, 30, 1.0, 160, 160);
  RebakeOptions o;
  o.width = o.height = 160, o.role = RebakeRole::Color;
  const Bakes b = bake_both(src, L, o);
  REQUIRE(b.stats.solved);
  const double e_area = surface_rms(src, b.area, L, true), e_lsq = surface_rms(src, b.lsq, L, true);
  std::printf("lsq 30deg: area %.5f lsq %.5f ratio %.3f iterations %u residual %.2e -> %.2e objective %.4g -> %.4g "
              "samples %zu unknowns %zu seconds %.3f\n",
              e_area, e_lsq, e_lsq / e_area, b.stats.iterations, b.stats.initial_residual, b.stats.final_residual,
              b.stats.initial_objective, b.stats.final_objective, b.stats.samples, b.stats.unknowns, b.stats.seconds);
  CHECK(b.stats.final_objective < b.stats.initial_objective);
  CHECK(b.stats.final_residual < 1e-4);
  CHECK(e_lsq < 0.75 * e_area);
}

TEST_CASE("rebake_lsq: an identity layout returns the source texels", "[atlas][lsq]") {
  for (RebakeRole role : {RebakeRole::Color, RebakeRole::Data}) {
    for (uint32_t channels : {3u, 4u}) {
      const Image src = detailed_image(64, 48, channels);
      Layout L;
      L.idx = {0, 1, 2, 0, 2, 3};
      L.old_uv = L.new_uv = {6.f / 64, 5.f / 48, 58.f / 64, 5.f / 48, 58.f / 64, 43.f / 48, 6.f / 64, 43.f / 48};
      RebakeOptions o;
      o.width = 64, o.height = 48, o.role = role;
      const Bakes b = bake_both(src, L, o);
      REQUIRE(b.stats.solved);
      // Inside the chart: texels 6..57 x 5..42 (every texel of the chart, its border included).
      double worst = 0;
      for (uint32_t y = 5; y < 43; ++y)
        for (uint32_t x = 6; x < 58; ++x)
          for (uint32_t c = 0; c < channels; ++c)
            worst = std::max(worst, double(std::abs(b.lsq.at(x, y, c) - src.at(x, y, c))));
      INFO("role " << int(role) << " channels " << channels << " worst " << worst << " iterations "
                   << b.stats.iterations << " residual " << b.stats.initial_residual << " -> " << b.stats.final_residual
                   << " objective " << b.stats.initial_objective << " -> " << b.stats.final_objective);
      CHECK(worst < 1e-5);
    }
  }
}

TEST_CASE("rebake_lsq: the same bytes whatever the thread count", "[atlas][lsq]") {
  const Image src = detailed_image(96, 96, 4);
  const Layout L = grid_layout(8, 80, 6, 96, 96, 23, 0.83, 96, 96);
  RebakeOptions o;
  o.width = o.height = 96, o.role = RebakeRole::Color;
  const int before = omp_get_max_threads();
  omp_set_num_threads(1);
  const Bakes one = bake_both(src, L, o);
  omp_set_num_threads(2);
  const Bakes two = bake_both(src, L, o);
  omp_set_num_threads(3);
  const Bakes three = bake_both(src, L, o);
  omp_set_num_threads(before);
  REQUIRE(one.stats.solved);
  CHECK(one.lsq.pixels == two.lsq.pixels);
  CHECK(one.lsq.pixels == three.lsq.pixels);
  CHECK(one.stats.iterations == two.stats.iterations);
}

TEST_CASE("rebake_lsq: a 0.7 downscale loses no more than the area filter", "[atlas][lsq]") {
  const Image src = detailed_image(128, 128, 3);
  for (double degrees : {0.0, 30.0}) {
    const Layout L = grid_layout(16, 96, 8, 128, 128, degrees, 0.7, 112, 112);
    RebakeOptions o;
    o.width = o.height = 112, o.role = RebakeRole::Color;
    const Bakes b = bake_both(src, L, o);
    REQUIRE(b.stats.solved);
    const double e_area = surface_rms(src, b.area, L, true), e_lsq = surface_rms(src, b.lsq, L, true);
    std::printf("lsq 0.7 downscale %.0fdeg: area %.5f lsq %.5f ratio %.3f iterations %u seconds %.3f\n", degrees,
                e_area, e_lsq, e_lsq / e_area, b.stats.iterations, b.stats.seconds);
    CHECK(e_lsq <= e_area);
  }
}

TEST_CASE("rebake_lsq: normal maps keep the area bake, mismatched inputs throw", "[atlas][lsq]") {
  const Image src = detailed_image(32, 32, 3);
  const Layout L = grid_layout(4, 24, 2, 32, 32, 30, 1.0, 32, 32);
  RebakeOptions o;
  o.width = o.height = 32, o.role = RebakeRole::Normal;
  const Bakes b = bake_both(src, L, o);
  CHECK_FALSE(b.stats.solved);
  CHECK(b.lsq.pixels == b.area.pixels);
  Image wrong = b.area;
  wrong.width = 16;
  CHECK_THROWS_AS(atlas::rebake_least_squares(src, {L.mesh()}, o, wrong), std::invalid_argument);
}

TEST_CASE("rebake_lsq: a Lanczos start's surround survives the solve where `keep` marks it", "[atlas][lsq]") {
  // A dark chart (the square [16, 48)^2 of a 64^2 white source) moved 3 texels right at the
  // same density, as in rebake_lanczos's surround test: the chart covers x in [19, 51), and
  // a surround of 4 bakes the source's white into x 15..18 and 51..54. The solve reaches
  // the first ring (its targets, footprint filters past the edge, see white there too); the
  // gutter past it is refilled from the solved texels, which near the image origin's 4x4
  // blocks mixes in the chart's dark at x 15 (0.63). With `keep` every surround texel keeps
  // the Lanczos start's white, and the fill continues it for as far again.
  const test::DarkChartOnWhite chart;
  const Image& src = chart.source;
  const atlas::RebakeMesh mesh = chart.mesh();
  RebakeOptions o;
  o.width = o.height = 64;
  o.role = RebakeRole::Data;
  o.surround = 4;
  const Image area = atlas::rebake(src, {mesh}, o, test::cpu_engine());
  std::vector<uint8_t> baked;
  const Image start = atlas::rebake_lanczos(src, {mesh}, o, area, &baked);
  atlas::LsqBakeStats stats;
  const Image kept = atlas::rebake_least_squares(src, {mesh}, o, start, &stats, {}, &baked);
  const Image plain = atlas::rebake_least_squares(src, {mesh}, o, start);
  REQUIRE(stats.solved);
  for (uint32_t y = 20; y < 44; ++y) {
    for (uint32_t x : {15u, 16u, 17u, 18u, 51u, 52u, 53u, 54u}) {
      INFO("x " << x << " y " << y);
      CHECK(kept.at(x, y, 0) > 0.95f);
      CHECK(baked[size_t(y) * 64 + x] == 1);
    }
    CHECK(plain.at(15, y, 0) < 0.9f);  // refilled: not the source's white
    CHECK(kept.at(30, y, 0) == Approx(0.1f).margin(2e-3));  // the chart's texels are solved the same
    CHECK(kept.at(30, y, 0) == plain.at(30, y, 0));
    CHECK(kept.at(58, y, 0) == kept.at(54, y, 0));  // past the surround: its outer texels continued
    CHECK(plain.at(58, y, 0) < 0.9f);                 // no surround kept: refilled from the solved texels
  }
  std::vector<uint8_t> wrong(7, 1);
  CHECK_THROWS_AS(atlas::rebake_least_squares(src, {mesh}, o, start, nullptr, {}, &wrong), std::invalid_argument);
}
