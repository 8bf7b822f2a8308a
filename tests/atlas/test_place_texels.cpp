#include <catch2/catch.hpp>

#include "atlas/place_texels.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

using namespace uvpress;

TEST_CASE("place_texels: a snapped chart's texels are copied under each quarter turn", "[atlas]") {
  // Every source texel holds its own index, so a copied texel names where it came from.
  Image src;
  src.width = 16, src.height = 12, src.channels = 1;
  src.pixels.resize(16 * 12);
  for (size_t i = 0; i < src.pixels.size(); ++i) src.pixels[i] = float(i);
  // An 8 x 6 chart on texel lines [2, 10] x [3, 9].
  atlas::ChartShape chart{{2, 3, 10, 3, 10, 9, 2, 9}, {0, 1, 2, 0, 2, 3}, true};
  for (uint32_t k = 0; k < 4; ++k) {
    INFO("quarter turns " << k);
    atlas::Packing p;
    p.ok = true, p.width = 24, p.height = 24, p.scale = 1;
    p.placements.resize(1);
    atlas::ChartPlacement& pl = p.placements[0];
    pl.rotation = k;
    // t puts the turned chart's box corner at (5, 4): found through map() itself.
    double lo[2] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
    for (size_t v = 0; v < 4; ++v) {
      auto q = p.map(0, chart.points[2 * v], chart.points[2 * v + 1]);
      lo[0] = std::min(lo[0], q[0]), lo[1] = std::min(lo[1], q[1]);
    }
    pl.tx = 5 - lo[0], pl.ty = 4 - lo[1];
    pl.x = 5, pl.y = 4, pl.width = k % 2 ? 6 : 8, pl.height = k % 2 ? 8 : 6;
    Image atlas;
    atlas.width = 24, atlas.height = 24, atlas.channels = 1;
    atlas.pixels.assign(24 * 24, -1.0f);
    CHECK(atlas::copy_chart_texels(src, chart, p, 0, 0, atlas) == 48);
    size_t checked = 0;
    for (uint32_t y = 0; y < 24; ++y)
      for (uint32_t x = 0; x < 24; ++x) {
        const float v = atlas.at(x, y, 0);
        if (v < 0) continue;
        // Invert the placement at the texel centre by solving map(p) = centre (R_k is
        // orthogonal: R_k^-1 = R_k^T).
        auto o = p.map(0, 0, 0), ex = p.map(0, 1, 0), ey = p.map(0, 0, 1);
        const double cx = x + 0.5 - o[0], cy = y + 0.5 - o[1];
        const double sx = cx * (ex[0] - o[0]) + cy * (ex[1] - o[1]);
        const double sy = cx * (ey[0] - o[0]) + cy * (ey[1] - o[1]);
        const uint32_t ix = uint32_t(std::floor(sx)), iy = uint32_t(std::floor(sy));
        CHECK(v == src.at(ix, iy, 0));
        CHECK(ix >= 2);
        CHECK(ix < 10);
        CHECK(iy >= 3);
        CHECK(iy < 9);
        ++checked;
      }
    CHECK(checked == 48);
  }
}

TEST_CASE("place_texels: a pinned chart is copied from the source itself while the packing shrinks the others",
          "[atlas]") {
  // Every source texel holds its own index. The 8 x 6 chart is pinned (ChartShape::pinned):
  // packed at scale 1 beside two 30 x 30 charts that only fit much smaller, so its texels
  // are the source's own, one for one, whatever the packing's scale.
  Image src;
  src.width = 16, src.height = 12, src.channels = 1;
  src.pixels.resize(16 * 12);
  for (size_t i = 0; i < src.pixels.size(); ++i) src.pixels[i] = float(i);
  atlas::ChartShape chart{{2, 3, 10, 3, 10, 9, 2, 9}, {0, 1, 2, 0, 2, 3}, true};
  chart.pinned = true;
  const atlas::ChartShape big{{0, 0, 30, 0, 30, 30, 0, 30}, {0, 1, 2, 0, 2, 3}};
  const std::vector<atlas::ChartShape> charts = {big, chart, big};
  atlas::PackOptions opt;
  opt.gutter = 2;
  const atlas::Packing p = atlas::pack_max_scale(charts, 40, 24, opt);
  REQUIRE(p.ok);
  CHECK(p.scale < 0.6);
  CHECK(p.placements[1].scale == 1.0);
  Image atlas;
  atlas.width = 40, atlas.height = 24, atlas.channels = 1;
  atlas.pixels.assign(40 * 24, -1.0f);
  CHECK(atlas::copy_chart_texels(src, chart, p, 1, 0, atlas) == 48);
  size_t checked = 0;
  auto o = p.map(1, 0, 0), ex = p.map(1, 1, 0), ey = p.map(1, 0, 1);
  for (uint32_t y = 0; y < 24; ++y)
    for (uint32_t x = 0; x < 40; ++x) {
      const float v = atlas.at(x, y, 0);
      if (v < 0) continue;
      const double cx = x + 0.5 - o[0], cy = y + 0.5 - o[1];
      const double sx = cx * (ex[0] - o[0]) + cy * (ex[1] - o[1]), sy = cx * (ey[0] - o[0]) + cy * (ey[1] - o[1]);
      CHECK(v == src.at(uint32_t(std::floor(sx)), uint32_t(std::floor(sy)), 0));
      ++checked;
    }
  CHECK(checked == 48);
}
