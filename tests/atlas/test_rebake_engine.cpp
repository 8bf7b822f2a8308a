// Re-bake on the engine: the Vulkan kernel (rebake.comp, fp32 relative to each texel with
// exact corner terms) against the CPU kernel (engine/cpu/rebake_texels.cpp, double), on
// random layouts, with the validation layer on. Stated tolerances (values in [0,1], after
// the host's conversions):
//   coverage                          identical (the host picks owners for both)
//   data and normal textures, alpha   |difference| <= 2e-6 per channel
//   colour (re-encoded to sRGB)       |difference| <= 1e-5 per channel (the encode's slope
//                                     is up to 12.92)
// Measured on lavapipe: at most 3e-7 in every case below. Chart layouts (charts apart, as
// the packer makes them) must meet these everywhere. Triangle soups (overlapping triangles
// from unrelated places of the source) may differ more where a sample lies within fp32
// rounding of an edge between two unrelated triangles: there at most 0.2% of the texels
// may exceed the tolerance.
#include <catch2/catch.hpp>

#include "atlas/rebake.h"
#include "engine.h"
#include "support.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <vector>

using namespace uvpress;
using atlas::RebakeMesh;
using atlas::RebakeOptions;
using atlas::RebakeRole;

namespace {

// Smooth structure plus 8-bit noise; alpha (the last of 2 or 4 channels) in [alpha_min, 1],
// and exactly 0 in a band when `holes` (fully transparent footprints: the straight pass).
Image test_image(uint32_t w, uint32_t h, uint32_t channels, std::mt19937& rng, float alpha_min, bool holes) {
  std::uniform_real_distribution<float> u(0, 1);
  Image im;
  im.width = w, im.height = h, im.channels = channels;
  im.pixels.resize(size_t(w) * h * channels);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x)
      for (uint32_t c = 0; c < channels; ++c) {
        float v = 0.5f + 0.3f * std::sin(0.21f * x + 1.7f * c) * std::cos(0.13f * y) + 0.2f * (u(rng) - 0.5f);
        v = std::round(std::clamp(v, 0.0f, 1.0f) * 255.0f) / 255.0f;
        const bool alpha = (channels == 4 && c == 3) || (channels == 2 && c == 1);
        if (alpha) v = (holes && (x / 8) % 3 == 0) ? 0.0f : alpha_min + (1 - alpha_min) * v;
        im.at(x, y, c) = v;
      }
  return im;
}

// A tangent-space normal map: unit normals tilted smoothly and by noise, 8-bit encoded; a
// fourth channel is noise.
Image normal_image(uint32_t w, uint32_t h, uint32_t channels, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(0, 1);
  Image im = test_image(w, h, channels, rng, 0.0f, false);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const float nx = 0.4f * std::sin(0.17f * x) + 0.2f * (u(rng) - 0.5f);
      const float ny = 0.4f * std::cos(0.11f * y) + 0.2f * (u(rng) - 0.5f);
      const float n[3] = {nx, ny, std::sqrt(std::max(0.0f, 1 - nx * nx - ny * ny))};
      for (uint32_t c = 0; c < 3; ++c) im.at(x, y, c) = std::round((n[c] + 1) * 0.5f * 255.0f) / 255.0f;
    }
  return im;
}

struct Layout {
  std::vector<uint32_t> idx;
  std::vector<float> ouv, nuv;
  RebakeMesh mesh() const { return {idx.data(), idx.size(), ouv.data(), nuv.data(), ouv.size() / 2}; }
};

// Charts as the packer leaves them: a cx x cy grid of cells in the new image, one chart a
// cell, each a jittered grid mesh rotated, scaled and sometimes mirrored, mapped from a
// random rotated, anisotropically scaled region of the source (partly outside [0,1]: wrap).
Layout random_charts(std::mt19937& rng, int cx, int cy, double old_min, double old_max) {
  std::uniform_real_distribution<double> u(0, 1);
  Layout L;
  for (int cj = 0; cj < cy; ++cj)
    for (int ci = 0; ci < cx; ++ci) {
      const int g = 2 + int(u(rng) * 5);  // vertices per side
      const uint32_t base = uint32_t(L.ouv.size() / 2);
      const double th = 6.283 * u(rng), ph = 6.283 * u(rng);
      const bool mirror = u(rng) < 0.3;
      const double side = 0.62 * (0.7 + 0.3 * u(rng));  // of a cell: fits at any angle
      const double ox = -0.15 + 0.9 * u(rng), oy = -0.15 + 0.9 * u(rng);
      const double sx = old_min + (old_max - old_min) * u(rng), sy = old_min + (old_max - old_min) * u(rng);
      for (int j = 0; j < g; ++j)
        for (int i = 0; i < g; ++i) {
          double s = double(i) / (g - 1), t = double(j) / (g - 1);
          if (i > 0 && i < g - 1) s += (u(rng) - 0.5) * 0.3 / (g - 1);
          if (j > 0 && j < g - 1) t += (u(rng) - 0.5) * 0.3 / (g - 1);
          const double a = (mirror ? 0.5 - s : s - 0.5) * side, b = (t - 0.5) * side;
          L.nuv.push_back(float((ci + 0.5 + std::cos(th) * a - std::sin(th) * b) / cx));
          L.nuv.push_back(float((cj + 0.5 + std::sin(th) * a + std::cos(th) * b) / cy));
          const double p = s * sx, q = t * sy;
          L.ouv.push_back(float(ox + std::cos(ph) * p - std::sin(ph) * q));
          L.ouv.push_back(float(oy + std::sin(ph) * p + std::cos(ph) * q));
        }
      for (int j = 0; j + 1 < g; ++j)
        for (int i = 0; i + 1 < g; ++i) {
          const uint32_t a = base + uint32_t(j * g + i);
          L.idx.insert(L.idx.end(), {a, a + 1, a + uint32_t(g) + 1, a, a + uint32_t(g) + 1, a + uint32_t(g)});
        }
    }
  return L;
}

// Independent random triangles, overlapping one another.
Layout random_soup(std::mt19937& rng, int count) {
  std::uniform_real_distribution<double> u(0, 1);
  Layout L;
  for (int k = 0; k < count; ++k) {
    const double x = u(rng), y = u(rng), r = 0.03 + 0.25 * u(rng);
    const double ox = u(rng), oy = u(rng), s = 0.2 + 2.0 * u(rng);
    for (int v = 0; v < 3; ++v) {
      const double dx = (u(rng) - 0.5) * r, dy = (u(rng) - 0.5) * r;
      L.nuv.push_back(float(x + dx)), L.nuv.push_back(float(y + dy));
      L.ouv.push_back(float(ox + s * dx + 0.3 * (u(rng) - 0.5) * r));
      L.ouv.push_back(float(oy + s * dy + 0.3 * (u(rng) - 0.5) * r));
      L.idx.push_back(uint32_t(L.idx.size()));
    }
  }
  return L;
}

struct Diff {
  double max = 0;
  size_t over = 0;  // texels with a channel beyond the tolerance
};

// CPU oracle vs Vulkan: coverage must be identical; returns the channel differences.
Diff compare(engine::Engine& vk, const Image& src, const std::vector<RebakeMesh>& meshes, const RebakeOptions& o,
             double tol_colour, double tol_alpha) {
  atlas::RebakeStats cs, vs;
  const Image a = atlas::rebake(src, meshes, o, test::cpu_engine(), &cs);
  const Image b = atlas::rebake(src, meshes, o, vk, &vs);
  REQUIRE(cs.covered > 0);
  REQUIRE(cs.coverage == vs.coverage);
  REQUIRE(a.pixels.size() == b.pixels.size());
  const uint32_t C = src.channels;
  const bool has_alpha = C == 2 || C == 4;
  Diff d;
  for (size_t i = 0; i < size_t(o.width) * o.height; ++i) {
    bool over = false;
    // Gutter texels are host code on both sides (atlas/gutter_fill.h): averages of many
    // covered texels, re-encoded to sRGB for colour, whose slope near black multiplies the
    // covered texels' difference (up to ~5x where a mean of bright and dark is dim).
    const double scale = cs.coverage[i] ? 1.0 : 5.0;
    for (uint32_t c = 0; c < C; ++c) {
      const double e = std::abs(double(a.pixels[i * C + c]) - b.pixels[i * C + c]);
      d.max = std::max(d.max, e);
      over = over || e > scale * (has_alpha && c == C - 1 ? tol_alpha : tol_colour);
    }
    d.over += over;
  }
  return d;
}

}  // namespace

TEST_CASE("rebake on the engine: Vulkan matches the CPU kernel on random chart layouts", "[atlas][vulkan]") {
  UVPRESS_LAVAPIPE_OR_SKIP(vk);
  std::mt19937 rng(7);
  struct Case {
    uint32_t channels;
    RebakeRole role;
    int wrap;
    uint32_t src_w, src_h, out_w, out_h;
    double old_min, old_max;  // source region size, fraction of the source
  };
  const Case cases[] = {
      {4, RebakeRole::Color, atlas::kWrapRepeat, 160, 128, 96, 80, 0.2, 0.6},         // downscale, premultiplied
      {3, RebakeRole::Color, atlas::kWrapClampToEdge, 128, 128, 200, 168, 0.1, 0.3},  // upscale
      {1, RebakeRole::Data, atlas::kWrapMirroredRepeat, 96, 112, 64, 64, 0.3, 0.9},   // strong downscale
      {2, RebakeRole::Data, atlas::kWrapRepeat, 128, 96, 120, 100, 0.2, 0.5},
      {4, RebakeRole::Data, atlas::kWrapClampToEdge, 128, 128, 64, 72, 0.2, 0.7},
      {3, RebakeRole::Normal, atlas::kWrapRepeat, 128, 128, 100, 100, 0.2, 0.6},
      {4, RebakeRole::Normal, atlas::kWrapMirroredRepeat, 96, 96, 80, 90, 0.2, 0.6},
  };
  int k = 0;
  for (const Case& c : cases) {
    for (int rep = 0; rep < 2; ++rep, ++k) {
      INFO("case " << k << ": channels " << c.channels << ", role " << int(c.role));
      const Image src = c.role == RebakeRole::Normal ? normal_image(c.src_w, c.src_h, c.channels, rng)
                                                     : test_image(c.src_w, c.src_h, c.channels, rng, 0.3f, false);
      const Layout L = random_charts(rng, 3 + rep, 3, c.old_min, c.old_max);
      RebakeOptions o;
      o.width = c.out_w, o.height = c.out_h, o.role = c.role;
      o.wrap_s = c.wrap, o.wrap_t = rep ? atlas::kWrapRepeat : c.wrap;
      const double tol = c.role == RebakeRole::Color ? 1e-5 : 2e-6;
      const Diff d = compare(*vk, src, {L.mesh()}, o, tol, 2e-6);
      INFO("max difference " << d.max);
      CHECK(d.over == 0);
    }
  }
  CHECK(vk->validation_errors() == 0);
}

TEST_CASE("rebake on the engine: transparent footprints, several meshes, buffer chunking", "[atlas][vulkan]") {
  // 48 KiB buffers: the 96 x 80 RGBA source (120 KiB) is split over three buffers, and the
  // new image goes one tile row per submit.
  UVPRESS_LAVAPIPE_OR_SKIP(vk, 48 * 1024);
  std::mt19937 rng(11);
  const Image src = test_image(96, 80, 4, rng, 0.0f, true);
  const Layout a = random_charts(rng, 3, 2, 0.2, 0.6), b = random_charts(rng, 2, 2, 0.3, 0.8);
  // b's charts in the right half of the new image, a's in the left.
  Layout a2 = a, b2 = b;
  for (size_t i = 0; i < a2.nuv.size(); i += 2) a2.nuv[i] *= 0.5f;
  for (size_t i = 0; i < b2.nuv.size(); i += 2) b2.nuv[i] = 0.5f + 0.5f * b2.nuv[i];
  RebakeOptions o;
  o.width = 150, o.height = 90;
  for (RebakeRole role : {RebakeRole::Color, RebakeRole::Data}) {
    o.role = role;
    const Diff d = compare(*vk, src, {a2.mesh(), b2.mesh()}, o, role == RebakeRole::Color ? 1e-5 : 2e-6, 2e-6);
    INFO("max difference " << d.max);
    CHECK(d.over == 0);
  }
  CHECK(vk->validation_errors() == 0);
}

TEST_CASE("rebake on the engine: triangle soups agree but for edge ties", "[atlas][vulkan]") {
  UVPRESS_LAVAPIPE_OR_SKIP(vk);
  std::mt19937 rng(5);
  for (uint32_t channels : {1u, 4u}) {
    const Image src = test_image(128, 128, channels, rng, 0.2f, false);
    const Layout L = random_soup(rng, 120);
    RebakeOptions o;
    o.width = 112, o.height = 104;
    o.role = channels == 4 ? RebakeRole::Color : RebakeRole::Data;
    const Diff d = compare(*vk, src, {L.mesh()}, o, channels == 4 ? 1e-5 : 2e-6, 2e-6);
    INFO("max difference " << d.max << ", texels over " << d.over);
    CHECK(d.over <= size_t(o.width) * o.height / 500);
  }
  CHECK(vk->validation_errors() == 0);
}

TEST_CASE("rebake on the engine: the CPU backend gives the same bits on 1 and 3 threads", "[atlas][engine]") {
  engine::EngineOptions single, triple;
  single.threads = 1, triple.threads = 3;
  const auto one = engine::make_cpu_engine(single), three = engine::make_cpu_engine(triple);
  std::mt19937 rng(3);
  const Image src = test_image(128, 96, 4, rng, 0.0f, true);
  const Layout L = random_charts(rng, 4, 3, 0.2, 0.7);
  RebakeOptions o;
  o.width = 90, o.height = 70;
  for (RebakeRole role : {RebakeRole::Color, RebakeRole::Data, RebakeRole::Normal}) {
    o.role = role;
    const Image a = atlas::rebake(src, {L.mesh()}, o, *one);
    const Image b = atlas::rebake(src, {L.mesh()}, o, *three);
    CHECK(a.pixels == b.pixels);
  }
}
