// The UV overlap finder: the exact pair test against an independent clipped-area reference,
// the grid against every pair, and only new overlaps counted.
#include <catch2/catch.hpp>

#include "atlas/uv_overlap.h"

#include <cmath>
#include <random>
#include <vector>

using namespace uvpress;
using atlas::TrianglePair;

namespace {

bool overlap(std::array<double, 6> a, std::array<double, 6> b) {
  return atlas::triangles_overlap(&a[0], &a[2], &a[4], &b[0], &b[2], &b[4]);
}

// Area of the intersection of two triangles by Sutherland-Hodgman clipping (floating
// point): an independent reference, decisive away from zero.
double intersection_area(std::array<double, 6> a, std::array<double, 6> b) {
  auto signed2 = [](const std::array<double, 6>& t) {
    return (t[2] - t[0]) * (t[5] - t[1]) - (t[4] - t[0]) * (t[3] - t[1]);
  };
  if (signed2(a) == 0 || signed2(b) == 0) return 0;  // no interior
  if (signed2(a) < 0) std::swap(a[2], a[4]), std::swap(a[3], a[5]);
  if (signed2(b) < 0) std::swap(b[2], b[4]), std::swap(b[3], b[5]);
  std::vector<std::array<double, 2>> poly = {{a[0], a[1]}, {a[2], a[3]}, {a[4], a[5]}};
  for (int e = 0; e < 3 && !poly.empty(); ++e) {
    const double px = b[2 * e], py = b[2 * e + 1], qx = b[2 * ((e + 1) % 3)], qy = b[2 * ((e + 1) % 3) + 1];
    auto side = [&](const std::array<double, 2>& p) { return (qx - px) * (p[1] - py) - (qy - py) * (p[0] - px); };
    std::vector<std::array<double, 2>> out;
    for (size_t i = 0; i < poly.size(); ++i) {
      const auto &p = poly[i], &q = poly[(i + 1) % poly.size()];
      const double sp = side(p), sq = side(q);
      if (sp >= 0) out.push_back(p);
      if ((sp > 0 && sq < 0) || (sp < 0 && sq > 0)) {
        const double t = sp / (sp - sq);
        out.push_back({p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])});
      }
    }
    poly = std::move(out);
  }
  double area = 0;
  for (size_t i = 0; i < poly.size(); ++i) {
    const auto &p = poly[i], &q = poly[(i + 1) % poly.size()];
    area += p[0] * q[1] - q[0] * p[1];
  }
  return 0.5 * std::abs(area);
}

// Every pair tested directly: the reference for the grid.
std::vector<TrianglePair> all_pairs(const std::vector<double>& points, const std::vector<uint32_t>& triangles) {
  std::vector<TrianglePair> pairs;
  const size_t n = triangles.size() / 3;
  auto p = [&](size_t t, int k) { return &points[2 * triangles[3 * t + size_t(k)]]; };
  for (size_t s = 0; s < n; ++s)
    for (size_t t = s + 1; t < n; ++t)
      if (atlas::triangles_overlap(p(s, 0), p(s, 1), p(s, 2), p(t, 0), p(t, 1), p(t, 2)))
        pairs.push_back({uint32_t(s), uint32_t(t)});
  return pairs;
}

}  // namespace

TEST_CASE("uv overlap: neighbours touch, folds, nesting, crossings and duplicates overlap", "[atlas][overlap]") {
  const std::array<double, 6> t = {0, 0, 4, 0, 0, 4};
  CHECK_FALSE(overlap(t, {4, 0, 0, 4, 4, 4}));       // shared edge, opposite sides
  CHECK(overlap(t, {4, 0, 0, 4, 1, 1}));             // shared edge, folded onto the same side
  CHECK_FALSE(overlap(t, {4, 0, 8, 0, 8, 4}));       // shared vertex
  CHECK_FALSE(overlap(t, {0, 4, 4, 0, 8, -4}));      // along the same line, the other side
  CHECK_FALSE(overlap(t, {0, 0, 4, 0, 2, -3}));      // shared edge below
  CHECK(overlap(t, t));                              // coincident
  CHECK(overlap(t, {0, 0, 0, 4, 4, 0}));             // mirrored duplicate (opposite orientation)
  CHECK(overlap(t, {0, 0, 4, 0, 0, 2}));             // third vertex on an edge: inside, no crossing
  CHECK(overlap(t, {1, 1, 2, 1, 1, 2}));             // nested
  CHECK(overlap(t, {-1, 1, 5, 1, 2, 9}));            // edges cross
  CHECK_FALSE(overlap(t, {5, 5, 6, 5, 5, 6}));       // apart
  CHECK_FALSE(overlap(t, {1, 1, 2, 2, 3, 3}));       // degenerate: no interior
  CHECK_FALSE(overlap(t, {2, 2, 3, 1, 3, 3}));       // touching the hypotenuse at a vertex from outside
  // One unit in the last place decides: a vertex exactly on the hypotenuse x + y = 1 touches,
  // a vertex just below it is inside.
  const double h = 0.5, below = std::nextafter(0.5, 0.0);
  const std::array<double, 6> u = {0, 0, 1, 0, 0, 1};
  CHECK_FALSE(overlap(u, {h, h, 1, 1, 2, -1}));
  CHECK(overlap(u, {h, below, 1, 1, 2, -1}));
  // Inexact decimals along one line (0.1 + 0.9 t, 0.7 - 0.3 t): collinear only up to rounding,
  // decided by the exact sign, the same either way round.
  const std::array<double, 6> v = {0.1, 0.7, 1.0, 0.4, 0.1, 1.5};
  const std::array<double, 6> w = {1.0, 0.4, 0.1, 0.7, 1.9, 0.1};
  CHECK(overlap(v, w) == overlap(w, v));
}

TEST_CASE("uv overlap: the pair test agrees with the clipped area on random lattice triangles", "[atlas][overlap]") {
  // Small integer coordinates: shared vertices, collinear edges and vertices on edges are
  // common, and the clipped area is either 0 or far from it.
  std::mt19937 rng(12);
  std::uniform_int_distribution<int> c(0, 4);
  size_t positive = 0, touching = 0;
  for (int i = 0; i < 20000; ++i) {
    std::array<double, 6> a, b;
    for (double& x : a) x = c(rng);
    for (double& x : b) x = c(rng);
    const double area = intersection_area(a, b);
    INFO(a[0] << "," << a[1] << " " << a[2] << "," << a[3] << " " << a[4] << "," << a[5] << " | " << b[0] << ","
              << b[1] << " " << b[2] << "," << b[3] << " " << b[4] << "," << b[5] << " area " << area);
    REQUIRE((area > 1e-9 || area < 1e-12));
    REQUIRE(overlap(a, b) == (area > 1e-9));
    REQUIRE(overlap(a, b) == overlap(b, a));
    positive += area > 1e-9;
    touching += area < 1e-12 && std::abs((a[2] - a[0]) * (a[5] - a[1]) - (a[4] - a[0]) * (a[3] - a[1])) > 0 &&
                std::abs((b[2] - b[0]) * (b[5] - b[1]) - (b[4] - b[0]) * (b[3] - b[1])) > 0;
  }
  CHECK(positive > 2000);
  CHECK(touching > 2000);
}

TEST_CASE("uv overlap: the grid finds exactly the pairs a test of every pair finds", "[atlas][overlap]") {
  std::mt19937 rng(7);
  SECTION("random soups: lattice points (shared vertices and edges) and scattered sizes") {
    for (int round = 0; round < 30; ++round) {
      const int n = 20 + 40 * round;
      std::vector<double> points;
      std::vector<uint32_t> triangles;
      std::uniform_int_distribution<int> lattice(0, 12 + round);
      std::uniform_real_distribution<double> r(0, 30), size(0.01, round % 3 == 0 ? 10.0 : 2.0);
      for (int i = 0; i < 3 * n; ++i) {
        if (round % 2) points.push_back(lattice(rng)), points.push_back(lattice(rng));
        else points.push_back(r(rng)), points.push_back(r(rng));
      }
      for (int t = 0; t < n; ++t) {
        std::uniform_int_distribution<uint32_t> v(0, uint32_t(3 * n - 1));
        if (round % 2) {
          triangles.insert(triangles.end(), {v(rng), v(rng), v(rng)});
        } else {
          // A small triangle near a random point, sharing a vertex with a random earlier one.
          const uint32_t a = v(rng), base = uint32_t(points.size() / 2);
          points.push_back(points[2 * a] + size(rng)), points.push_back(points[2 * a + 1]);
          points.push_back(points[2 * a]), points.push_back(points[2 * a + 1] + size(rng));
          triangles.insert(triangles.end(), {a, base, base + 1});
        }
      }
      // Mirrored duplicates of a few triangles.
      for (int t = 0; t < n / 10; ++t) {
        const size_t s = size_t(t) * 7 % size_t(n);
        triangles.insert(triangles.end(), {triangles[3 * s], triangles[3 * s + 2], triangles[3 * s + 1]});
      }
      INFO("round " << round);
      CHECK(atlas::find_overlaps(points.data(), triangles.data(), triangles.size() / 3) == all_pairs(points, triangles));
    }
  }
  SECTION("a folded grid mesh: neighbours never count, the fold does") {
    // 10 x 10 quads, two triangles each; then the column x = 5 pushed past x = 6.
    std::vector<double> points;
    std::vector<uint32_t> triangles;
    for (int y = 0; y <= 10; ++y)
      for (int x = 0; x <= 10; ++x) points.push_back(x), points.push_back(y);
    for (uint32_t y = 0; y < 10; ++y)
      for (uint32_t x = 0; x < 10; ++x) {
        const uint32_t a = y * 11 + x;
        triangles.insert(triangles.end(), {a, a + 1, a + 12, a, a + 12, a + 11});
      }
    CHECK(atlas::find_overlaps(points.data(), triangles.data(), triangles.size() / 3).empty());
    std::vector<double> folded = points;
    for (int y = 0; y <= 10; ++y) folded[2 * size_t(y * 11 + 5)] = 6.5;
    const auto pairs = atlas::find_overlaps(folded.data(), triangles.data(), triangles.size() / 3);
    CHECK(!pairs.empty());
    CHECK(pairs == all_pairs(folded, triangles));
  }
}

TEST_CASE("uv overlap: only overlaps the input did not have are new", "[atlas][overlap]") {
  // Triangle 1 mirrors triangle 0 in the input (they share texels); triangle 2 is apart.
  const std::vector<uint32_t> triangles = {0, 1, 2, 3, 4, 5, 6, 7, 8};
  const std::vector<double> before = {0, 0, 2, 0, 0, 2, /**/ 0, 0, 0, 2, 2, 0, /**/ 5, 5, 7, 5, 5, 7};
  std::vector<double> after = before;
  CHECK(atlas::find_new_overlaps(before.data(), after.data(), triangles.data(), 3).empty());
  // Triangle 2 moved onto both.
  for (size_t k = 12; k < 18; ++k) after[k] -= 4.5;
  CHECK(atlas::find_overlaps(after.data(), triangles.data(), 3) == std::vector<TrianglePair>{{0, 1}, {0, 2}, {1, 2}});
  CHECK(atlas::find_new_overlaps(before.data(), after.data(), triangles.data(), 3) == std::vector<TrianglePair>{{0, 2}, {1, 2}});
}
