#include <catch2/catch.hpp>

#include "atlas/pack.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

using namespace uvpress;
using atlas::ChartShape;
using atlas::ChartPlacement;
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

// At least `g` empty texels between charts (any direction), `ex` to the left and right
// image edges and `ey` to the top and bottom ones (-1: g).
bool gutters_hold(const std::vector<int>& label, uint32_t W, uint32_t H, int g, int ex = -1, int ey = -1) {
  if (ex < 0) ex = g;
  if (ey < 0) ey = g;
  for (int y = 0; y < int(H); ++y)
    for (int x = 0; x < int(W); ++x) {
      const int l = label[size_t(y) * W + x];
      if (!l) continue;
      if (x < ex || y < ey || x >= int(W) - ex || y >= int(H) - ey) return false;
      for (int dy = -g; dy <= g; ++dy)
        for (int dx = -g; dx <= g; ++dx) {
          if (x + dx < 0 || y + dy < 0 || x + dx >= int(W) || y + dy >= int(H)) continue;
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
  // Efficiency: texels under the charts over the image; charts that do not overlap cover
  // about their area (texel centres, so within a few percent at these sizes).
  CHECK(p.efficiency == Approx(p.covered / (160.0 * 128.0)));
  CHECK(p.covered == Approx(p.chart_area).epsilon(0.05));
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

TEST_CASE("pack: block alignment for BCn (4) and ASTC 5x5, 6x6, 8x8", "[atlas]") {
  const auto charts = random_charts(30, 11);
  for (const uint32_t b : {4u, 5u, 6u, 8u}) {
    INFO("block " << b);
    const uint32_t side = 48 * b;  // whole blocks
    PackOptions opt;
    opt.gutter = 3;
    opt.block = b;
    Packing p = atlas::pack_max_scale(charts, side, side, opt, 1.0);
    REQUIRE(p.ok);
    std::vector<int> label;
    CHECK(label_atlas(charts, p, label));
    CHECK(gutters_hold(label, side, side, 3));
    for (const auto& pl : p.placements) {
      CHECK(pl.x % b == 0);
      CHECK(pl.y % b == 0);
      CHECK(pl.width % b == 0);
      CHECK(pl.height % b == 0);
    }
    // No b x b block holds texels of two charts, and charts keep a whole block apart.
    int shared = 0;
    for (uint32_t by = 0; by < side / b; ++by)
      for (uint32_t bx = 0; bx < side / b; ++bx) {
        int seen = 0;
        for (uint32_t y = 0; y < b; ++y)
          for (uint32_t x = 0; x < b; ++x) {
            const int l = label[size_t(b * by + y) * side + b * bx + x];
            if (l && seen && l != seen) ++shared;
            if (l) seen = l;
          }
      }
    CHECK(shared == 0);
    CHECK(gutters_hold(label, side, side, int(b)));  // the gutter rounds up to one block
  }
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

TEST_CASE("pack: pinned charts stay at the source density, aligned, while the others take the slack", "[atlas]") {
  // A 40 x 40 chart copied from the source (snapped, at multiples of 8) and 24 others that
  // do not fit at scale 1: the bisection shrinks only the others.
  std::vector<ChartShape> charts = random_charts(24, 11);
  ChartShape copy = rect(11.25, 13.5, 40, 40);  // its snapped origin (8, 8): on the 8-texel phase
  copy.snap = true, copy.align = 8, copy.pinned = true;
  charts.insert(charts.begin() + 5, copy);
  PackOptions opt;
  const Packing p = atlas::pack_max_scale(charts, 128, 96, opt, 1.0, 1e-4);
  REQUIRE(p.ok);
  REQUIRE(p.scale < 0.9);  // the others were shrunk...
  CHECK(p.placements[5].scale == 1.0);  // ...the pinned chart was not
  for (size_t i = 0; i < charts.size(); ++i)
    if (i != 5) CHECK(p.placements[i].scale == p.scale);
  // Its points land at scale 1, moved by a whole multiple of 8 texels (any quarter turn).
  const auto a = p.map(5, 11.25, 13.5), b = p.map(5, 51.25, 13.5), c = p.map(5, 11.25, 53.5);
  CHECK(std::hypot(b[0] - a[0], b[1] - a[1]) == Approx(40.0).epsilon(1e-12));
  CHECK(std::hypot(c[0] - a[0], c[1] - a[1]) == Approx(40.0).epsilon(1e-12));
  const ChartPlacement& pl = p.placements[5];
  INFO("rotation " << pl.rotation << ", t (" << pl.tx << ", " << pl.ty << ")");
  CHECK(std::fmod(pl.tx, 8.0) == 0.0);  // source texel (i, j) lands on an atlas texel of the same 8-phase
  CHECK(std::fmod(pl.ty, 8.0) == 0.0);
  CHECK(pl.x % 8 == 0);
  CHECK(pl.y % 8 == 0);
  // The packing is valid as placed (footprints apart by the gutter, inside the image), and
  // maximal for the others: 0.1 % more scale does not fit.
  std::vector<int> label;
  CHECK(label_atlas(charts, p, label));
  CHECK(gutters_hold(label, p.width, p.height, int(opt.gutter)));
  CHECK_FALSE(atlas::pack_charts(charts, 128, 96, p.scale * (1 + 1e-3), opt).ok);
  // Uniformly scaled instead, the copy shrinks with the rest: pinning is what keeps it.
  for (ChartShape& ch : charts) ch.pinned = false;
  const Packing u = atlas::pack_max_scale(charts, 128, 96, opt, 1.0, 1e-4);
  REQUIRE(u.ok);
  CHECK(u.placements[5].scale == u.scale);
  CHECK(u.scale < 1.0);
  // Pinned charts that alone overfill the image, or that fit in area but not in shape (a
  // 130-texel bar in a 128-texel image): no packing, at any scale of the others.
  std::vector<ChartShape> big = {rect(0, 0, 200, 200), rect(0, 0, 10, 10)};
  big[0].pinned = true;
  CHECK_FALSE(atlas::pack_max_scale(big, 128, 96, opt).ok);
  big[0] = rect(0, 0, 130, 10), big[0].pinned = true;
  CHECK_FALSE(atlas::pack_max_scale(big, 128, 96, opt).ok);
  // Under a chart-texel budget (eq. 21) the pinned chart's texels are spent first, at 1,
  // and the others' scale buys what is left: 1600 + s^2 * 4 * 1600 = 0.5 * (1600 + 4 * 1600).
  std::vector<ChartShape> four = {copy, rect(0, 0, 40, 40), rect(0, 0, 40, 40), rect(0, 0, 40, 40), rect(0, 0, 40, 40)};
  atlas::BudgetOptions bo;
  bo.cost = 0.5;
  bo.measure = atlas::CostMeasure::ChartTexels;
  const double old_used = 5 * 1600.0;
  const auto choice = atlas::choose_atlas(four, 256, 256, old_used, bo);
  REQUIRE(choice.packing.ok);
  CHECK(choice.packing.placements[0].scale == 1.0);
  CHECK(choice.packing.scale == Approx(std::sqrt((0.5 * old_used - 1600) / 6400)).epsilon(1e-9));
  CHECK(choice.cost_ratio == Approx(0.5).epsilon(1e-6));
  // A budget the pinned chart alone overspends buys nothing; every chart pinned, there is
  // no scale to choose and the charts pack at 1.
  bo.cost = 0.15;  // 1200 texels of chart, against the pinned chart's 1600
  CHECK_FALSE(atlas::choose_atlas(four, 256, 256, old_used, bo).packing.ok);
  for (ChartShape& ch : four) ch.pinned = true;
  bo.cost = 1;
  bo.s_max = 2;  // the packing's scale is then s_max: the placements must still say 1
  const auto all = atlas::choose_atlas(four, 256, 256, old_used, bo);
  REQUIRE(all.packing.ok);
  for (const ChartPlacement& q : all.packing.placements) CHECK(q.scale == 1.0);
  CHECK(all.cost_ratio == Approx(1.0).epsilon(1e-9));
  bo.cost = 0.9;  // every chart pinned and the budget short of them
  CHECK_FALSE(atlas::choose_atlas(four, 256, 256, old_used, bo).packing.ok);
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

  o.measure = atlas::CostMeasure::ChartTexels;
  o.cost = 0.3;
  for (const uint32_t b : {4u, 6u}) {
    o.pack.block = b;
    auto cb = atlas::choose_atlas(charts, 1024, 512, old_used, o);
    REQUIRE(cb.packing.ok);
    CHECK(cb.packing.width % b == 0);
    CHECK(cb.packing.height % b == 0);
  }
}

TEST_CASE("pack: holes inside and between charts are refilled", "[atlas]") {
  // A 40 x 40 square ring (walls 6 wide) and a 20 x 20 square that only fits in its hole:
  // the atlas is 52 x 52 with gutter 2, so the ring fills it and nothing fits beside it.
  ChartShape ring;
  ring.points = {0, 0, 40, 0, 40, 40, 0, 40, 6, 6, 34, 6, 34, 34, 6, 34};
  ring.triangles = {0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
  const std::vector<ChartShape> charts = {ring, rect(100, 100, 20, 20)};
  PackOptions opt;
  opt.gutter = 2;
  Packing p = atlas::pack_charts(charts, 46, 46, 1.0, opt);
  REQUIRE(p.ok);
  std::vector<int> label;
  CHECK(label_atlas(charts, p, label));
  CHECK(gutters_hold(label, 46, 46, 2));
  // The square sits inside the ring's hole.
  const auto& r = p.placements[0];
  const auto& q = p.placements[1];
  CHECK(q.x >= r.x + 6);
  CHECK(q.y >= r.y + 6);
  CHECK(q.x + q.width <= r.x + 34);
  CHECK(q.y + q.height <= r.y + 34);
  // Under an overhang: an upside-down U (a 60 x 10 bar over two 10 x 30 legs) leaves a
  // 40 x 30 hole open at the bottom; four 16 x 12 boxes fit only there.
  ChartShape u;
  u.points = {0, 0, 60, 0, 60, 40, 50, 40, 50, 10, 10, 10, 10, 40, 0, 40};
  u.triangles = {0, 1, 4, 0, 4, 5, 1, 2, 3, 1, 3, 4, 0, 5, 6, 0, 6, 7};
  std::vector<ChartShape> under = {u};
  for (int i = 0; i < 4; ++i) under.push_back(rect(0, 0, 16, 12));
  PackOptions no_turn;
  no_turn.gutter = 1;
  no_turn.rotate = false;
  Packing h = atlas::pack_charts(under, 62, 42, 1.0, no_turn);
  REQUIRE(h.ok);
  CHECK(label_atlas(under, h, label));
  CHECK(gutters_hold(label, 62, 42, 1));
}

TEST_CASE("pack: all four quarter turns map charts where their footprints are", "[atlas]") {
  // A right triangle with its right angle in each corner in turn fits a 2-texel-gutter
  // 40 x 40 atlas beside a big L only in one orientation; whichever turn is chosen, the
  // map puts every vertex inside its placement box (label_atlas checks) and the texels
  // never overlap.
  for (int corner = 0; corner < 4; ++corner) {
    ChartShape t = tri(0, 0, 20, 0, 0, 20);
    for (size_t k = 0; k < t.points.size(); k += 2) {
      double& x = t.points[k];
      double& y = t.points[k + 1];
      for (int r = 0; r < corner; ++r) {
        const double nx = -y, ny = x;
        x = nx, y = ny;
      }
    }
    const std::vector<ChartShape> charts = {ell(0, 0, 36, 36, 12), t};
    PackOptions opt;
    opt.gutter = 2;
    Packing p = atlas::pack_charts(charts, 40, 40, 1.0, opt);
    INFO("corner " << corner);
    REQUIRE(p.ok);
    std::vector<int> label;
    CHECK(label_atlas(charts, p, label));
    CHECK(gutters_hold(label, 40, 40, 2));
  }
}

TEST_CASE("pack: edge gutters apart from the gutter (a sampler that clamps needs none, one that repeats half)", "[atlas]") {
  // A 40 x 24 texel rectangle fills a 40 x 24 atlas when the edges need no gutter (clamp).
  ChartShape rect;
  rect.points = {0, 0, 40, 0, 40, 24, 0, 24};
  rect.triangles = {0, 1, 2, 0, 2, 3};
  PackOptions clamp;
  clamp.gutter = 8, clamp.edge_x = clamp.edge_y = 0;
  Packing p = atlas::pack_charts({rect}, 40, 24, 1.0, clamp);
  REQUIRE(p.ok);
  CHECK(p.efficiency == Approx(1.0));
  CHECK(p.gutter_texels == 0);
  // With the gutter at the edges (the default) it does not fit; with half of it on a
  // repeating axis (atlas::edge_gutter) it fits exactly that much larger.
  PackOptions as_gutter;
  as_gutter.gutter = 8;
  CHECK_FALSE(atlas::pack_charts({rect}, 40, 24, 1.0, as_gutter).ok);
  CHECK(atlas::pack_charts({rect}, 56, 40, 1.0, as_gutter).ok);
  PackOptions wrap_u = clamp;
  wrap_u.edge_x = atlas::edge_gutter(8, true);
  CHECK(wrap_u.edge_x == 4);
  CHECK(atlas::edge_gutter(8, false) == 0);
  CHECK_FALSE(atlas::pack_charts({rect}, 47, 24, 1.0, wrap_u).ok);
  p = atlas::pack_charts({rect}, 48, 24, 1.0, wrap_u);
  REQUIRE(p.ok);
  std::vector<int> label;
  CHECK(label_atlas({rect}, p, label));
  CHECK(gutters_hold(label, 48, 24, 8, 4, 0));
  CHECK_FALSE(gutters_hold(label, 48, 24, 8, 5, 0));
  // Many charts: the gutter between them still holds when the edges take less.
  const auto charts = random_charts(40, 11);
  PackOptions mixed;
  mixed.gutter = 4, mixed.edge_x = 2, mixed.edge_y = 0;
  Packing m = atlas::pack_max_scale(charts, 128, 96, mixed, 1.0);
  REQUIRE(m.ok);
  CHECK(label_atlas(charts, m, label));
  CHECK(gutters_hold(label, 128, 96, 4, 2, 0));
  // Less edge, more scale (the same charts with the gutter at every edge).
  PackOptions full;
  full.gutter = 4;
  CHECK(m.scale > atlas::pack_max_scale(charts, 128, 96, full, 1.0).scale);
}

TEST_CASE("pack: overlapping charts count their texels once, gutters are counted", "[atlas]") {
  // Two copies of one 20 x 10 rectangle in one shape (a mirrored pair sharing texels).
  ChartShape pair = rect(0, 0, 20, 10);
  pair.points.insert(pair.points.end(), {0, 0, 20, 0, 20, 10, 0, 10});
  pair.triangles.insert(pair.triangles.end(), {4, 5, 6, 4, 6, 7});
  PackOptions opt;
  opt.gutter = 3;
  Packing p = atlas::pack_charts({pair}, 64, 32, 1.0, opt);
  REQUIRE(p.ok);
  CHECK(p.chart_area == Approx(400.0));  // eq. 20 counts both
  CHECK(p.covered == Approx(200.0));      // the image holds them once
  CHECK(p.efficiency == Approx(200.0 / (64 * 32)));
  // Gutter texels: those within 3 of the footprint or of the edge, not under it (brute force).
  const auto& pl = p.placements[0];
  double expected = 0;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 64; ++x) {
      const bool under = x >= int(pl.x) && x < int(pl.x + pl.width) && y >= int(pl.y) && y < int(pl.y + pl.height);
      const bool near_edge = x < 3 || y < 3 || x >= 61 || y >= 29;
      const bool near_chart = x >= int(pl.x) - 3 && x < int(pl.x + pl.width) + 3 && y >= int(pl.y) - 3 && y < int(pl.y + pl.height) + 3;
      expected += !under && (near_edge || near_chart);
    }
  CHECK(p.gutter_texels == Approx(expected));
}

TEST_CASE("pack: a long chart gets a long atlas when the aspect is free", "[atlas]") {
  // A 480 x 24 bar and a few squares from a 512 x 512 source, at a quarter of its texels.
  std::vector<ChartShape> charts = {rect(0, 0, 480, 24)};
  for (int i = 0; i < 4; ++i) charts.push_back(rect(0, 0, 60, 60));
  atlas::BudgetOptions o;
  o.measure = atlas::CostMeasure::ImageTexels;
  o.cost = 0.25;
  o.keep_aspect = true;
  auto square = atlas::choose_atlas(charts, 512, 512, 0, o);
  REQUIRE(square.packing.ok);
  CHECK(square.packing.width == square.packing.height);
  o.keep_aspect = false;
  auto free = atlas::choose_atlas(charts, 512, 512, 0, o);
  REQUIRE(free.packing.ok);
  INFO("square " << square.packing.width << "x" << square.packing.height << " scale " << square.packing.scale << ", free "
                 << free.packing.width << "x" << free.packing.height << " scale " << free.packing.scale);
  CHECK(free.packing.width > free.packing.height);  // the bar lies along the long side
  CHECK(free.packing.scale > 1.3 * square.packing.scale);
  CHECK(free.packing.scale == 1.0);  // at the source density: the atlas shrank to fit
  CHECK(free.texel_ratio <= 0.25);  // within the budget
  // Four squares (2 x 2 in a square atlas) keep the source's shape.
  std::vector<ChartShape> squares(4, rect(0, 0, 60, 60));
  auto kept = atlas::choose_atlas(squares, 512, 512, 0, o);
  REQUIRE(kept.packing.ok);
  CHECK(kept.packing.width == kept.packing.height);
}

TEST_CASE("pack: a shape between the source's and 2:1 when the charts want it", "[atlas]") {
  // A 480 x 400 chart (6:5) from a 512 x 512 source at a quarter of its texels (65,536):
  // the square atlas (256 x 256) holds it at scale (256 - 8) / 480 = 0.517, a 2^(1/4):1
  // one (279 x 234: 279 x 235 would be 29 texels over the budget) at min(271 / 480,
  // 226 / 400) = 0.565, 2:1 (362 x 181) at 0.433.
  const std::vector<ChartShape> charts = {rect(0, 0, 480, 400)};
  atlas::BudgetOptions o;
  o.measure = atlas::CostMeasure::ImageTexels;
  o.cost = 0.25;
  o.keep_aspect = true;
  const auto square = atlas::choose_atlas(charts, 512, 512, 0, o);
  REQUIRE(square.packing.ok);
  CHECK(square.packing.width == 256);
  CHECK(square.packing.scale == Approx(248.0 / 480).epsilon(2e-3));
  o.keep_aspect = false;
  const auto free = atlas::choose_atlas(charts, 512, 512, 0, o);
  REQUIRE(free.packing.ok);
  INFO("free " << free.packing.width << "x" << free.packing.height << " scale " << free.packing.scale);
  // Either way round: the chart may take a quarter turn.
  CHECK(std::max(free.packing.width, free.packing.height) == 279);
  CHECK(std::min(free.packing.width, free.packing.height) == 234);
  CHECK(free.packing.scale == Approx(271.0 / 480).epsilon(2e-3));
  CHECK(free.texel_ratio <= 0.25);  // the same budget, never a texel over
  // A 436 x 400 chart (1.09:1): the square holds it at 248 / 436 = 0.569, the grid's
  // 1.19:1 at min(271 / 436, 227 / 400) = 0.568, its own shape (and 2^(1/8):1 about the
  // square), 267 x 245, at min(259 / 436, 237 / 400) = 0.5925 (a step of 2^(1/16) about
  // it would be 267 x 246, 146 texels over the budget: it too gets 245).
  const std::vector<ChartShape> near_square = {rect(0, 0, 436, 400)};
  const auto near = atlas::choose_atlas(near_square, 512, 512, 0, o);
  REQUIRE(near.packing.ok);
  INFO("near " << near.packing.width << "x" << near.packing.height << " scale " << near.packing.scale);
  CHECK(std::max(near.packing.width, near.packing.height) == 267);
  CHECK(std::min(near.packing.width, near.packing.height) == 245);
  CHECK(near.packing.scale >= 0.59);  // the square's 0.569 + 4 %
  CHECK(near.texel_ratio <= 0.25);
}

TEST_CASE("pack: an image-texel budget is never exceeded, whatever the shape chosen", "[atlas]") {
  // Each side of a non-square atlas is rounded on its own; before the shorter side gave
  // way, the demo at half its texels got 316 x 415 = 0.5003 of them. Sources of three
  // shapes, costs down to a tenth, the shape fixed and free, BCn blocks and none.
  const std::vector<std::vector<ChartShape>> sets = {random_charts(12, 3), {rect(0, 0, 480, 400)}, {rect(0, 0, 300, 130)}};
  size_t checked = 0, shapes_off_square = 0;
  for (const auto& charts : sets)
    for (auto [W, H] : {std::pair{512u, 512u}, std::pair{1024u, 512u}, std::pair{640u, 480u}})
      for (double cost : {0.1, 0.25, 0.37, 0.5, 0.7})
        for (bool keep : {true, false})
          for (uint32_t block : {1u, 4u}) {
            atlas::BudgetOptions o;
            o.measure = atlas::CostMeasure::ImageTexels;
            o.cost = cost, o.keep_aspect = keep, o.pack.block = block, o.pack.gutter = 2;
            const auto c = atlas::choose_atlas(charts, W, H, 0, o);
            if (!c.packing.ok) continue;
            INFO(W << "x" << H << " cost " << cost << " keep " << keep << " block " << block << ": " << c.packing.width << "x"
                   << c.packing.height);
            CHECK(double(c.packing.width) * c.packing.height <= cost * W * H);
            CHECK(c.packing.width % block == 0);
            CHECK(c.packing.height % block == 0);
            ++checked, shapes_off_square += c.packing.width * H != c.packing.height * W;
          }
  CHECK(checked >= 150);
  CHECK(shapes_off_square > 0);  // the free shapes were exercised
  // A square source in BCn blocks of 8 at half its texels: 362 a side rounds up to 368, over
  // the budget; the square gives way whole (360 x 360), not its shorter side (368 x 352).
  atlas::BudgetOptions o;
  o.measure = atlas::CostMeasure::ImageTexels;
  o.cost = 0.5, o.pack.block = 8, o.pack.gutter = 2;
  const auto sq = atlas::choose_atlas({rect(0, 0, 500, 500)}, 512, 512, 0, o);
  REQUIRE(sq.packing.ok);
  CHECK(sq.packing.width == 360);
  CHECK(sq.packing.height == 360);
}

TEST_CASE("pack: the same packing on any thread count", "[atlas]") {
  const auto charts = random_charts(40, 5);
  atlas::BudgetOptions o;
  o.measure = atlas::CostMeasure::ImageTexels;
  o.cost = 0.02;
  o.keep_aspect = false;
  const int before = omp_get_max_threads();
  omp_set_num_threads(1);
  const auto a = atlas::choose_atlas(charts, 1024, 1024, 0, o);
  omp_set_num_threads(2);
  const auto b = atlas::choose_atlas(charts, 1024, 1024, 0, o);
  omp_set_num_threads(before);
  REQUIRE(a.packing.ok);
  REQUIRE(b.packing.ok);
  CHECK(a.packing.width == b.packing.width);
  CHECK(a.packing.height == b.packing.height);
  CHECK(a.packing.scale == b.packing.scale);
  for (size_t c = 0; c < charts.size(); ++c) {
    CHECK(a.packing.placements[c].tx == b.packing.placements[c].tx);
    CHECK(a.packing.placements[c].ty == b.packing.placements[c].ty);
    CHECK(a.packing.placements[c].rotation == b.packing.placements[c].rotation);
  }
}

TEST_CASE("pack: mip-phase alignment: copied charts move by multiples of align under every quarter turn", "[atlas]") {
  CHECK(atlas::mip_phase_align(8, 1) == 8);
  CHECK(atlas::mip_phase_align(16, 1) == 16);
  CHECK(atlas::mip_phase_align(12, 1) == 8);
  CHECK(atlas::mip_phase_align(8, 4) == 8);
  CHECK(atlas::mip_phase_align(8, 5) == 1);  // no power of two on a 5-texel grid
  CHECK(atlas::mip_phase_align(1, 1) == 1);
  CHECK(atlas::mip_phase_align(0, 1) == 1);
  // Snapped charts at fractional positions (as unreshaped units arrive), some tall so that
  // the packer turns them, among unsnapped ones that may go anywhere.
  std::vector<ChartShape> charts = random_charts(24, 5);
  for (size_t i = 0; i < charts.size(); ++i) {
    if (i % 4 == 3) continue;
    charts[i].snap = true;
    charts[i].align = 8;
  }
  PackOptions opt;
  opt.gutter = 4;
  for (const double scale : {1.0, 0.75}) {
    INFO("scale " << scale);
    const Packing p = atlas::pack_max_scale(charts, 400, 300, opt, scale);
    REQUIRE(p.ok);
    std::vector<int> label;
    CHECK(label_atlas(charts, p, label));
    CHECK(gutters_hold(label, 400, 300, 4));
    uint32_t turned = 0;
    for (size_t i = 0; i < charts.size(); ++i) {
      const auto& pl = p.placements[i];
      if (!charts[i].snap) continue;
      INFO("chart " << i << " turns " << pl.rotation << " t " << pl.tx << " " << pl.ty);
      CHECK(std::fmod(pl.tx, 8.0) == 0);
      CHECK(std::fmod(pl.ty, 8.0) == 0);
      turned += pl.rotation != 0;
    }
    CHECK(turned > 0);
  }
  // Unaligned, the same snapped charts land on texels but not on every 8th (else this
  // test could not tell).
  for (auto& c : charts) c.align = 1;
  const Packing p = atlas::pack_max_scale(charts, 400, 300, opt, 1.0);
  REQUIRE(p.ok);
  size_t off = 0;
  for (size_t i = 0; i < charts.size(); ++i)
    if (charts[i].snap) off += std::fmod(p.placements[i].tx, 8.0) != 0 || std::fmod(p.placements[i].ty, 8.0) != 0;
  CHECK(off > 0);
}

TEST_CASE("pack: sides multiples of side_multiple, within an image-texel budget", "[atlas]") {
  const auto charts = random_charts(20, 3);
  atlas::BudgetOptions o;
  o.measure = atlas::CostMeasure::ImageTexels;
  o.keep_aspect = false;
  o.pack.gutter = 4;
  for (const double cost : {0.3, 0.5}) {
    for (const uint32_t m : {8u, 16u}) {
      INFO("cost " << cost << " side multiple " << m);
      o.cost = cost, o.side_multiple = m;
      const auto c = atlas::choose_atlas(charts, 500, 400, 0, o);
      REQUIRE(c.packing.ok);
      CHECK(c.packing.width % m == 0);
      CHECK(c.packing.height % m == 0);
      CHECK(double(c.packing.width) * c.packing.height <= cost * 500 * 400);
    }
  }
  // A block that does not divide it leaves the block's own rule.
  o.side_multiple = 16, o.pack.block = 6, o.cost = 0.5;
  const auto c = atlas::choose_atlas(charts, 500, 400, 0, o);
  REQUIRE(c.packing.ok);
  CHECK(c.packing.width % 6 == 0);
  CHECK(c.packing.height % 6 == 0);
}
