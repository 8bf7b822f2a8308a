#include <catch2/catch.hpp>

#include "atlas/pack.h"

#include <algorithm>
#include <cstdint>
#include <vector>

using namespace uvpress;
using atlas::ChartShape;
using atlas::Packing;
using atlas::PackOptions;

namespace {

ChartShape rect(double x, double y, double w, double h) {
  return {{x, y, x + w, y, x + w, y + h, x, y + h}, {0, 1, 2, 0, 2, 3}};
}

// An L: a w x t bar along the top and a t x h bar down the left side.
ChartShape ell(double x, double y, double w, double h, double t) {
  return {{x, y, x + w, y, x + w, y + t, x + t, y + t, x + t, y + h, x, y + h}, {0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 5}};
}

ChartShape tri(double x0, double y0, double x1, double y1, double x2, double y2) {
  return {{x0, y0, x1, y1, x2, y2}, {0, 1, 2}};
}

uint32_t lcg(uint32_t& s) {
  s = s * 1664525u + 1013904223u;
  return s >> 8;
}

std::vector<ChartShape> random_charts(int n, uint32_t seed) {
  std::vector<ChartShape> charts;
  for (int i = 0; i < n; ++i) {
    const double x = lcg(seed) % 1000 - 500.25, y = lcg(seed) % 1000 + 0.37;
    const double w = 3 + lcg(seed) % 40 + 0.3, h = 3 + lcg(seed) % 40 + 0.6;
    switch (i % 3) {
      case 0: charts.push_back(rect(x, y, w, h)); break;
      case 1: charts.push_back(ell(x, y, w, h, std::min(w, h) / 3)); break;
      default: charts.push_back(tri(x, y, x + w, y + 0.2 * h, x + 0.4 * w, y + h)); break;
    }
  }
  return charts;
}

// Rasterizes every placed chart into the atlas (label = chart + 1), as the re-bake will.
// Returns false on overlap or on a texel outside the atlas.
bool label_atlas(const std::vector<ChartShape>& charts, const Packing& p, std::vector<int>& label) {
  label.assign(size_t(p.width) * p.height, 0);
  bool ok = true;
  for (size_t c = 0; c < charts.size(); ++c) {
    const auto& ch = charts[c];
    std::vector<uint8_t> mine(label.size(), 0);
    for (size_t t = 0; t < ch.triangles.size(); t += 3) {
      double v[3][2];
      for (int k = 0; k < 3; ++k) {
        auto q = p.map(c, ch.points[2 * ch.triangles[t + k]], ch.points[2 * ch.triangles[t + k] + 1]);
        v[k][0] = q[0], v[k][1] = q[1];
        // Every vertex inside the footprint box.
        if (q[0] < p.placements[c].x - 1e-6 || q[0] > p.placements[c].x + p.placements[c].width + 1e-6 ||
            q[1] < p.placements[c].y - 1e-6 || q[1] > p.placements[c].y + p.placements[c].height + 1e-6)
          ok = false;
      }
      const int x0 = int(std::floor(std::min({v[0][0], v[1][0], v[2][0]}))) - 1;
      const int x1 = int(std::ceil(std::max({v[0][0], v[1][0], v[2][0]}))) + 1;
      const int y0 = int(std::floor(std::min({v[0][1], v[1][1], v[2][1]}))) - 1;
      const int y1 = int(std::ceil(std::max({v[0][1], v[1][1], v[2][1]}))) + 1;
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          if (!atlas::triangle_overlaps_box(v[0], v[1], v[2], x, y, x + 1, y + 1)) continue;
          if (x < 0 || y < 0 || x >= int(p.width) || y >= int(p.height)) {
            ok = false;
            continue;
          }
          mine[size_t(y) * p.width + x] = 1;
        }
    }
    for (size_t i = 0; i < label.size(); ++i)
      if (mine[i]) {
        if (label[i] != 0) ok = false;
        label[i] = int(c) + 1;
      }
  }
  return ok;
}

// At least `g` empty texels between charts (any direction) and to the image edge.
bool gutters_hold(const std::vector<int>& label, uint32_t W, uint32_t H, int g) {
  for (int y = 0; y < int(H); ++y)
    for (int x = 0; x < int(W); ++x) {
      const int l = label[size_t(y) * W + x];
      if (!l) continue;
      if (x < g || y < g || x >= int(W) - g || y >= int(H) - g) return false;
      for (int dy = -g; dy <= g; ++dy)
        for (int dx = -g; dx <= g; ++dx) {
          const int m = label[size_t(y + dy) * W + x + dx];
          if (m && m != l) return false;
        }
    }
  return true;
}

}  // namespace

TEST_CASE("pack: no overlap, gutters and bounds hold, efficiency reported", "[atlas]") {
  const auto charts = random_charts(60, 7);
  PackOptions opt;
  opt.gutter = 3;
  Packing p = atlas::pack_max_scale(charts, 160, 128, opt, 1.0);
  REQUIRE(p.ok);
  CHECK(p.scale < 1.0);  // the charts are too big at 1: the scale shrank
  std::vector<int> label;
  CHECK(label_atlas(charts, p, label));
  CHECK(gutters_hold(label, p.width, p.height, 3));
  // Every chart got texels.
  for (size_t c = 0; c < charts.size(); ++c) CHECK(std::count(label.begin(), label.end(), int(c) + 1) > 0);
  CHECK(p.efficiency == Approx(p.chart_area / (160.0 * 128.0)));
  INFO("scale " << p.scale << " efficiency " << p.efficiency);
  CHECK(p.efficiency > 0.3);
  CHECK(p.efficiency < 1.0);
  // Deterministic.
  Packing q = atlas::pack_max_scale(charts, 160, 128, opt, 1.0);
  REQUIRE(q.placements.size() == p.placements.size());
  CHECK(q.scale == p.scale);
  for (size_t c = 0; c < charts.size(); ++c) {
    CHECK(q.placements[c].tx == p.placements[c].tx);
    CHECK(q.placements[c].ty == p.placements[c].ty);
    CHECK(q.placements[c].rotation == p.placements[c].rotation);
  }
}

TEST_CASE("pack: a tall chart in a wide atlas is rotated", "[atlas]") {
  const std::vector<ChartShape> charts = {rect(5.5, -3, 10, 40)};
  PackOptions opt;
  opt.gutter = 2;
  Packing p = atlas::pack_charts(charts, 64, 16, 1.0, opt);
  REQUIRE(p.ok);
  CHECK(p.placements[0].rotation == 1);
  CHECK(p.placements[0].width == 40);
  CHECK(p.placements[0].height == 10);
  std::vector<int> label;
  CHECK(label_atlas(charts, p, label));
  CHECK(gutters_hold(label, 64, 16, 2));
  opt.rotate = false;
  CHECK_FALSE(atlas::pack_charts(charts, 64, 16, 1.0, opt).ok);
}

TEST_CASE("pack: footprints interlock where bounding boxes cannot", "[atlas]") {
  // Two complementary 40x40 right triangles. As boxes they need 2*40 + 3*2 = 86 texels in
  // one direction; the atlas is 48 x 56.
  const std::vector<ChartShape> charts = {tri(0, 0, 40, 0, 0, 40), tri(140, 100, 140, 140, 100, 140)};
  PackOptions opt;
  opt.gutter = 2;
  Packing p = atlas::pack_charts(charts, 48, 56, 1.0, opt);
  REQUIRE(p.ok);
  std::vector<int> label;
  CHECK(label_atlas(charts, p, label));
  CHECK(gutters_hold(label, 48, 56, 2));
}

TEST_CASE("pack: block alignment for BCn", "[atlas]") {
  const auto charts = random_charts(30, 11);
  PackOptions opt;
  opt.gutter = 3;
  opt.block = 4;
  Packing p = atlas::pack_max_scale(charts, 256, 256, opt, 1.0);
  REQUIRE(p.ok);
  std::vector<int> label;
  CHECK(label_atlas(charts, p, label));
  CHECK(gutters_hold(label, 256, 256, 3));
  for (const auto& pl : p.placements) {
    CHECK(pl.x % 4 == 0);
    CHECK(pl.y % 4 == 0);
    CHECK(pl.width % 4 == 0);
    CHECK(pl.height % 4 == 0);
  }
  // No 4x4 block holds texels of two charts, and charts keep a whole block apart.
  int shared = 0;
  for (int by = 0; by < 64; ++by)
    for (int bx = 0; bx < 64; ++bx) {
      int seen = 0;
      for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) {
          const int l = label[size_t(4 * by + y) * 256 + 4 * bx + x];
          if (l && seen && l != seen) ++shared;
          if (l) seen = l;
        }
    }
  CHECK(shared == 0);
  CHECK(gutters_hold(label, 256, 256, 4));  // the gutter rounds up to one block
}

TEST_CASE("pack: the bisection scale is maximal", "[atlas]") {
  const auto charts = random_charts(25, 3);
  PackOptions opt;
  Packing p = atlas::pack_max_scale(charts, 120, 96, opt, 1.0, 1e-4);
  REQUIRE(p.ok);
  REQUIRE(p.scale < 1.0);
  CHECK(atlas::pack_charts(charts, 120, 96, p.scale, opt).ok);
  CHECK_FALSE(atlas::pack_charts(charts, 120, 96, p.scale * (1 + 1e-3), opt).ok);
  // Small charts: capped at s_max (the source density), never magnified.
  const std::vector<ChartShape> small = {rect(0, 0, 10, 10), rect(0, 0, 20, 5)};
  Packing q = atlas::pack_max_scale(small, 128, 128, opt, 1.0);
  REQUIRE(q.ok);
  CHECK(q.scale == 1.0);
  // Too many charts for the gutters: failure, not a crash.
  std::vector<ChartShape> many(400, rect(0, 0, 1, 1));
  CHECK_FALSE(atlas::pack_max_scale(many, 32, 32, opt).ok);
}

TEST_CASE("pack: atlas size from the budget", "[atlas]") {
  // Charts at the source density of a 1024 x 512 texture, covering 60 % of it.
  std::vector<ChartShape> charts;
  for (int i = 0; i < 6; ++i) charts.push_back(rect(0, 0, 200 + 10 * i, 150));
  double area = 0;
  for (int i = 0; i < 6; ++i) area += (200 + 10 * i) * 150.0;
  const double old_used = area;  // the input layout used exactly these texels

  atlas::BudgetOptions o;
  o.cost = 0.25;
  auto c = atlas::choose_atlas(charts, 1024, 512, old_used, o);
  REQUIRE(c.packing.ok);
  CHECK(c.cost_ratio == Approx(0.25).epsilon(1e-6));  // eq. 21 hit exactly without pot
  CHECK(c.packing.scale == Approx(0.5).epsilon(1e-9));
  CHECK(c.packing.width >= c.packing.height);  // the source aspect (2:1), roughly
  CHECK(double(c.packing.width) / c.packing.height == Approx(2.0).epsilon(0.1));
  // Minimal: the next smaller atlas of that aspect does not hold the charts at that scale.
  CHECK_FALSE(atlas::pack_charts(charts, c.packing.width - 2, c.packing.height - 1, 0.5, o.pack).ok);

  o.pot = true;
  auto cp = atlas::choose_atlas(charts, 1024, 512, old_used, o);
  REQUIRE(cp.packing.ok);
  CHECK((cp.packing.width & (cp.packing.width - 1)) == 0);
  CHECK((cp.packing.height & (cp.packing.height - 1)) == 0);
  CHECK(cp.packing.width == 2 * cp.packing.height);
  CHECK(cp.packing.scale <= 1.0);

  o.pot = false;
  o.size = 300;
  auto cs = atlas::choose_atlas(charts, 1024, 512, old_used, o);
  REQUIRE(cs.packing.ok);
  CHECK(cs.packing.width == 300);
  CHECK(cs.packing.height == 150);
  CHECK(cs.texel_ratio == Approx(300.0 * 150 / (1024.0 * 512)));

  o.size = 0;
  o.measure = atlas::CostMeasure::ImageTexels;
  o.cost = 0.5;
  auto ci = atlas::choose_atlas(charts, 1024, 512, old_used, o);
  REQUIRE(ci.packing.ok);
  CHECK(ci.texel_ratio == Approx(0.5).epsilon(0.01));
  CHECK(ci.packing.scale < 1.0);

  o.pack.block = 4;
  o.measure = atlas::CostMeasure::ChartTexels;
  o.cost = 0.3;
  auto cb = atlas::choose_atlas(charts, 1024, 512, old_used, o);
  REQUIRE(cb.packing.ok);
  CHECK(cb.packing.width % 4 == 0);
  CHECK(cb.packing.height % 4 == 0);
}
