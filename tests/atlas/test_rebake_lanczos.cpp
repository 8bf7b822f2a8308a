#include <catch2/catch.hpp>

#include "atlas/rebake.h"
#include "atlas/dark_chart_on_white.h"
#include "atlas/rebake_lanczos.h"
#include "eval/resize.h"
#include "support.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <vector>

using namespace uvpress;

namespace {

Image noise(uint32_t w, uint32_t h, uint32_t channels) {
  Image im;
  im.width = w, im.height = h, im.channels = channels;
  im.pixels.resize(size_t(w) * h * channels);
  uint32_t s = 12345;
  for (float& v : im.pixels) {
    s = s * 1664525u + 1013904223u;
    v = float((s >> 8) % 256) / 255.0f;
  }
  return im;
}

// One quad over the whole image, old UVs -> new UVs (both [0,1], v down).
struct Quad {
  std::vector<uint32_t> idx{0, 1, 2, 0, 2, 3};
  std::vector<float> old_uv{0, 0, 1, 0, 1, 1, 0, 1};
  std::vector<float> new_uv{0, 0, 1, 0, 1, 1, 0, 1};
  atlas::RebakeMesh mesh() const { return {idx.data(), idx.size(), old_uv.data(), new_uv.data(), 4}; }
};

}  // namespace

TEST_CASE("rebake_lanczos: a uniform half-size layout is the Lanczos-3 resize", "[atlas]") {
  const Image src = noise(64, 48, 3);
  const Quad q;
  atlas::RebakeOptions o;
  o.width = 32, o.height = 24;
  o.role = atlas::RebakeRole::Color;
  const Image area = atlas::rebake(src, {q.mesh()}, o, test::cpu_engine());
  const Image lz = atlas::rebake_lanczos(src, {q.mesh()}, o, area);
  // The reference: eval's Lanczos-3 resize in stored values (itself checked against a
  // double-precision reference and OpenImageIO's resize in test_eval.cpp).
  const Image ref = eval::resize_lanczos3(src, 32, 24, false);
  double worst = 0, worst_area = 0;
  for (uint32_t y = 4; y < 20; ++y)  // away from the edges (the resize clamps, the bake wraps)
    for (uint32_t x = 4; x < 28; ++x)
      for (uint32_t c = 0; c < 3; ++c) {
        worst = std::max(worst, double(std::abs(lz.at(x, y, c) - ref.at(x, y, c))));
        worst_area = std::max(worst_area, double(std::abs(area.at(x, y, c) - ref.at(x, y, c))));
      }
  INFO("lanczos bake vs resize " << worst << ", area bake vs resize " << worst_area);
  CHECK(worst < 2e-3);
  CHECK(worst_area > 0.05);  // the area filter is a different (blurrier) bake
}

TEST_CASE("rebake_lanczos: a turned, anisotropically shrunk chart is the Lanczos-3 kernel in the new texel axes", "[atlas]") {
  // The whole 64^2 source mapped by n = c + A (p - 32) (texels), A = R(30 deg) diag(0.4, 0.6):
  // both axes shrink, so the kernel's coordinates of a source offset d are A d (the
  // header's V min(S^-1, 1) U^T d with J = A^-1). The reference evaluates that kernel
  // directly, in double, over every source texel (repeat wrap); the bake reads a table of
  // the kernel and visits per source row only the span of taps inside the kernel's turned
  // square, so a wrong axis or a span cut short shows here, not in the uniform resize.
  const Image src = noise(64, 64, 3);
  const double ang = M_PI / 6, sx = 0.4, sy = 0.6, c = 24;
  const double A[2][2] = {{std::cos(ang) * sx, -std::sin(ang) * sy}, {std::sin(ang) * sx, std::cos(ang) * sy}};
  Quad q;
  for (int k = 0; k < 4; ++k) {
    const double px = q.old_uv[2 * k] * 64 - 32, py = q.old_uv[2 * k + 1] * 64 - 32;
    q.new_uv[2 * k] = float((c + A[0][0] * px + A[0][1] * py) / 48);
    q.new_uv[2 * k + 1] = float((c + A[1][0] * px + A[1][1] * py) / 48);
  }
  atlas::RebakeOptions o;
  o.width = o.height = 48;
  o.role = atlas::RebakeRole::Color;
  const Image lz = atlas::rebake_lanczos(src, {q.mesh()}, o, atlas::rebake(src, {q.mesh()}, o, test::cpu_engine()));
  const auto l3 = [](double k) { return std::abs(k) < 1e-12 ? 1.0 : 3 * std::sin(M_PI * k) * std::sin(M_PI * k / 3) / (M_PI * M_PI * k * k); };
  const double det = A[0][0] * A[1][1] - A[0][1] * A[1][0];
  double worst = 0;
  size_t checked = 0;
  for (uint32_t y = 0; y < 48; ++y)
    for (uint32_t x = 0; x < 48; ++x) {
      // The preimage of the texel centre; only texels 2 source texels inside the quad.
      const double nx = x + 0.5 - c, ny = y + 0.5 - c;
      const double ox = 32 + (A[1][1] * nx - A[0][1] * ny) / det, oy = 32 + (-A[1][0] * nx + A[0][0] * ny) / det;
      if (ox < 2 || oy < 2 || ox > 62 || oy > 62) continue;
      double acc[3] = {0, 0, 0}, wsum = 0;
      for (int ty = -20; ty < 84; ++ty)
        for (int tx = -20; tx < 84; ++tx) {
          const double dx = tx + 0.5 - ox, dy = ty + 0.5 - oy;
          const double kx = A[0][0] * dx + A[0][1] * dy, ky = A[1][0] * dx + A[1][1] * dy;
          if (std::abs(kx) >= 3 || std::abs(ky) >= 3) continue;
          const double w = l3(kx) * l3(ky);
          for (uint32_t ch = 0; ch < 3; ++ch) acc[ch] += w * src.at(uint32_t((tx + 64) % 64), uint32_t((ty + 64) % 64), ch);
          wsum += w;
        }
      for (uint32_t ch = 0; ch < 3; ++ch)
        worst = std::max(worst, std::abs(std::clamp(acc[ch] / wsum, 0.0, 1.0) - double(lz.at(x, y, ch))));
      ++checked;
    }
  INFO("texels checked " << checked << ", worst difference " << worst);
  CHECK(checked > 300);
  // Not closer: the bake's map comes from the float corners (~1e-6 texel off A), and unit
  // steps of noise move a Lanczos sum by ~10 per texel of shift (the kernel's table is within
  // 1e-7 of it). A wrong kernel is off by ~0.1, a tap missing at a span's end by ~1e-2.
  CHECK(worst < 1e-4);
}

TEST_CASE("rebake_lanczos: identity and quarter turns at the same size copy texels, normals keep the area bake", "[atlas]") {
  const Image src = noise(32, 32, 4);
  atlas::RebakeOptions o;
  o.width = 32, o.height = 32;
  o.role = atlas::RebakeRole::Data;
  Quad q;
  const Image same = atlas::rebake_lanczos(src, {q.mesh()}, o, atlas::rebake(src, {q.mesh()}, o, test::cpu_engine()));
  size_t changed = 0;
  for (size_t i = 0; i < src.pixels.size(); ++i) changed += std::abs(same.pixels[i] - src.pixels[i]) > 1e-6f;
  CHECK(changed == 0);
  // A quarter turn: new (u, v) = (1 - v_old, u_old) for the corners.
  q.new_uv = {1, 0, 1, 1, 0, 1, 0, 0};
  const Image turned =
      atlas::rebake_lanczos(src, {q.mesh()}, o, atlas::rebake(src, {q.mesh()}, o, test::cpu_engine()));
  size_t mismatched = 0;
  for (uint32_t y = 0; y < 32; ++y)
    for (uint32_t x = 0; x < 32; ++x)
      for (uint32_t c = 0; c < 4; ++c) mismatched += std::abs(turned.at(x, y, c) - src.at(y, 31 - x, c)) > 1e-6f;
  CHECK(mismatched == 0);
  // Deterministic whatever the thread count.
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  q.new_uv = {0.1f, 0.05f, 0.8f, 0.1f, 0.9f, 0.7f, 0.05f, 0.9f};
  o.width = 20, o.height = 20;
  const Image area = atlas::rebake(src, {q.mesh()}, o, test::cpu_engine());
  const Image a = atlas::rebake_lanczos(src, {q.mesh()}, o, area);
  omp_set_num_threads(2);
  const Image b = atlas::rebake_lanczos(src, {q.mesh()}, o, area);
  omp_set_num_threads(threads);
  CHECK(a.pixels == b.pixels);
  o.role = atlas::RebakeRole::Normal;
  CHECK(atlas::rebake_lanczos(src, {q.mesh()}, o, area).pixels == area.pixels);
}

TEST_CASE("rebake_lanczos: surround bakes what the source has around a chart into the gutter next to it", "[atlas]") {
  // A dark chart (the square [16, 48)^2 of a 64^2 source) on a white background, moved to
  // the middle of a 64^2 atlas at the same density. Next to its edge the gutter must show
  // the source's white up to `surround` texels; the fill then continues that white for as
  // far again (atlas::fill_ring), where a one-texel ring and the pull-push would put the
  // chart's dark (its block means).
  const test::DarkChartOnWhite chart;
  const Image& src = chart.source;
  const atlas::RebakeMesh mesh = chart.mesh();
  atlas::RebakeOptions o;
  o.width = o.height = 64;
  o.role = atlas::RebakeRole::Data;
  const Image area = atlas::rebake(src, {mesh}, o, test::cpu_engine());
  const Image plain = atlas::rebake_lanczos(src, {mesh}, o, area);
  o.surround = 4;
  std::vector<uint8_t> baked;
  const Image kept = atlas::rebake_lanczos(src, {mesh}, o, area, &baked);
  // The chart occupies x in [19, 51): texels 51..54 right of it, 15..18 left, lie within 4.
  for (uint32_t y = 20; y < 44; ++y) {
    for (uint32_t x : {15u, 16u, 17u, 18u, 51u, 52u, 53u, 54u}) {
      INFO("x " << x << " y " << y);
      CHECK(kept.at(x, y, 0) > 0.95f);  // the source's white around the chart
      CHECK(plain.at(x, y, 0) < 0.2f);  // without surround: the fill, the chart's dark
      CHECK(baked[size_t(y) * 64 + x] == 1);
    }
    CHECK(kept.at(30, y, 0) == Approx(0.1f).margin(1e-4));  // the chart itself is unchanged
    CHECK(kept.at(30, y, 0) == plain.at(30, y, 0));
    for (uint32_t x : {11u, 12u, 13u, 14u, 55u, 56u, 57u, 58u}) {  // past the surround: filled, not baked
      INFO("x " << x << " y " << y);
      CHECK(kept.at(x, y, 0) == kept.at(x < 32 ? 15 : 54, y, 0));  // the surround's outer texel, continued
      CHECK(baked[size_t(y) * 64 + x] == 0);
    }
    CHECK(plain.at(55, y, 0) < 0.2f);  // without a surround, a one-texel ring, then the chart's dark
  }
}

TEST_CASE("rebake_lanczos on an engine: the area bake only where it is kept, the same texels and coverage",
          "[atlas]") {
  // Two quads of one source: the first reshaped mildly (Lanczos everywhere), the second
  // squeezed 6x along u (past kMaxShrink: its texels keep the area bake's value). The
  // engine form filters only those by area; it must give, texel for texel, what the area
  // bake of every texel followed by the Lanczos bake gives, and the same coverage.
  const Image src = noise(96, 64, 4);
  const std::vector<uint32_t> idx{0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7};
  const std::vector<float> old_uv{0, 0, 0.5f, 0, 0.5f, 1, 0, 1, 0.5f, 0, 1, 0, 1, 1, 0.5f, 1};
  const std::vector<float> new_uv{0.05f, 0.05f, 0.45f, 0.08f, 0.5f, 0.9f, 0.02f, 0.95f,
                                  0.7f,  0.1f,  0.78f, 0.1f,  0.78f, 0.9f, 0.7f, 0.9f};
  const atlas::RebakeMesh mesh{idx.data(), idx.size(), old_uv.data(), new_uv.data(), 8};
  // The first quad alone: nothing left to the area bake (no engine call at all).
  const atlas::RebakeMesh mild{idx.data(), 6, old_uv.data(), new_uv.data(), 8};
  for (const auto& m : {mesh, mild})
  for (const auto role : {atlas::RebakeRole::Color, atlas::RebakeRole::Data, atlas::RebakeRole::Normal})
    for (uint32_t surround : {0u, 3u}) {
      atlas::RebakeOptions o;
      o.width = 48, o.height = 40;
      o.role = role, o.surround = surround;
      atlas::RebakeStats first;
      const Image area = atlas::rebake(src, {m}, o, test::cpu_engine(), &first);
      const Image want = atlas::rebake_lanczos(src, {m}, o, area, &first.coverage);
      atlas::RebakeStats stats;
      const Image got = atlas::rebake_lanczos(src, {m}, o, test::cpu_engine(), &stats);
      INFO("triangles " << m.index_count / 3 << " role " << int(role) << " surround " << surround);
      CHECK(got.pixels == want.pixels);
      CHECK(stats.coverage == first.coverage);
      CHECK(stats.covered == first.covered);
      CHECK(stats.triangles == first.triangles);
    }
  // The squeezed quad's texels did keep the area bake's value (so the check above covers
  // the texels filtered by area alone): its middle texel is not the Lanczos pass's zero.
  atlas::RebakeOptions o;
  o.width = 48, o.height = 40;
  const Image got = atlas::rebake_lanczos(src, {mesh}, o, test::cpu_engine());
  const Image area = atlas::rebake(src, {mesh}, o, test::cpu_engine());
  const uint32_t x = uint32_t(0.74 * 48), y = 20;
  for (uint32_t c = 0; c < 4; ++c) CHECK(got.at(x, y, c) == area.at(x, y, c));
  CHECK(got.at(x, y, 0) + got.at(x, y, 1) + got.at(x, y, 2) > 0.0f);
}
