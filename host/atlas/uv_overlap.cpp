#include "atlas/uv_overlap.h"

#include <algorithm>
#include <cmath>

namespace uvpress::atlas {

namespace {

// Error-free transformations (Knuth's two-sum; the product's error by one fused
// multiply-add): a + b = s + e and a * b = p + e exactly.
void two_sum(double a, double b, double& s, double& e) {
  s = a + b;
  const double bv = s - a;
  e = (a - (s - bv)) + (b - bv);
}
void two_product(double a, double b, double& p, double& e) {
  p = a * b;
  e = std::fma(a, b, -p);
}

// The exact sign of det [b - a, c - a] = bx cy - bx ay - ax cy - by cx + by ax + ay cx: the
// six products split into twelve doubles, summed into a nonoverlapping expansion (Shewchuk's
// grow-expansion), whose sign is that of its largest nonzero component.
int orientation_exact(const double a[2], const double b[2], const double c[2]) {
  const double factors[6][2] = {{b[0], c[1]}, {-b[0], a[1]}, {-a[0], c[1]}, {-b[1], c[0]}, {b[1], a[0]}, {a[1], c[0]}};
  double expansion[12];
  int n = 0;
  auto grow = [&](double x) {
    double q = x;
    for (int i = 0; i < n; ++i) two_sum(q, expansion[i], q, expansion[i]);
    expansion[n++] = q;
  };
  for (const auto& f : factors) {
    double p, e;
    two_product(f[0], f[1], p, e);
    grow(e);
    grow(p);
  }
  for (int i = n - 1; i >= 0; --i)
    if (expansion[i] != 0) return expansion[i] > 0 ? 1 : -1;
  return 0;
}

struct Box {
  double lo[2], hi[2];
};

}  // namespace

int orientation(const double a[2], const double b[2], const double c[2]) {
  // Shewchuk's filter (ccwerrboundA): when |det| exceeds this bound its rounded sign is right.
  const double left = (b[0] - a[0]) * (c[1] - a[1]), right = (b[1] - a[1]) * (c[0] - a[0]);
  const double det = left - right;
  const double bound = 3.3306690738754716e-16 * (std::abs(left) + std::abs(right));
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return orientation_exact(a, b, c);
}

bool triangles_overlap(const double a0[2], const double a1[2], const double a2[2], const double b0[2],
                       const double b1[2], const double b2[2]) {
  const int oa = orientation(a0, a1, a2), ob = orientation(b0, b1, b2);
  if (oa == 0 || ob == 0) return false;
  // Both counter-clockwise, so that an edge's outer side is where orientation() <= 0.
  const double* A[3] = {a0, oa > 0 ? a1 : a2, oa > 0 ? a2 : a1};
  const double* B[3] = {b0, ob > 0 ? b1 : b2, ob > 0 ? b2 : b1};
  auto separates = [](const double* const* P, const double* const* Q) {
    for (int i = 0; i < 3; ++i) {
      const double* p = P[i];
      const double* q = P[(i + 1) % 3];
      if (orientation(p, q, Q[0]) <= 0 && orientation(p, q, Q[1]) <= 0 && orientation(p, q, Q[2]) <= 0) return true;
    }
    return false;
  };
  return !separates(A, B) && !separates(B, A);
}

std::vector<TrianglePair> find_overlaps(const double* points, const uint32_t* triangles, size_t triangle_count) {
  auto corner = [&](size_t t, int k) { return &points[2 * size_t(triangles[3 * t + size_t(k)])]; };
  std::vector<uint32_t> active;
  std::vector<Box> box(triangle_count);
  Box all{{INFINITY, INFINITY}, {-INFINITY, -INFINITY}};
  double extent = 0;
  for (size_t t = 0; t < triangle_count; ++t) {
    bool finite = true;
    for (int k = 0; k < 3; ++k) finite = finite && std::isfinite(corner(t, k)[0]) && std::isfinite(corner(t, k)[1]);
    if (!finite || orientation(corner(t, 0), corner(t, 1), corner(t, 2)) == 0) continue;  // no interior
    Box& b = box[t];
    for (int d = 0; d < 2; ++d) {
      b.lo[d] = std::min({corner(t, 0)[d], corner(t, 1)[d], corner(t, 2)[d]});
      b.hi[d] = std::max({corner(t, 0)[d], corner(t, 1)[d], corner(t, 2)[d]});
      all.lo[d] = std::min(all.lo[d], b.lo[d]), all.hi[d] = std::max(all.hi[d], b.hi[d]);
    }
    extent += std::max(b.hi[0] - b.lo[0], b.hi[1] - b.lo[1]);
    active.push_back(uint32_t(t));
  }
  std::vector<TrianglePair> pairs;
  if (active.size() < 2) return pairs;

  // The grid: cells the size of the mean box, and no more cells than ~3 per triangle.
  const double n = double(active.size());
  const double span[2] = {all.hi[0] - all.lo[0], all.hi[1] - all.lo[1]};
  const double cell = std::max(extent / n, std::sqrt(span[0] * span[1] / n));
  int cells[2];
  for (int d = 0; d < 2; ++d) cells[d] = int(std::clamp(std::ceil(span[d] / cell), 1.0, n));
  auto cell_of = [&](double x, int d) {
    // Monotone in x, so a point between two boxes' corners falls between their cells.
    const double i = std::floor((x - all.lo[d]) / span[d] * cells[d]);
    return int(std::clamp(i, 0.0, double(cells[d] - 1)));
  };
  // Buckets in compressed rows: triangle ids ascending within each cell.
  const size_t cell_count = size_t(cells[0]) * size_t(cells[1]);
  std::vector<size_t> start(cell_count + 1, 0);
  auto for_cells = [&](uint32_t t, auto&& f) {
    const Box& b = box[t];
    for (int y = cell_of(b.lo[1], 1); y <= cell_of(b.hi[1], 1); ++y)
      for (int x = cell_of(b.lo[0], 0); x <= cell_of(b.hi[0], 0); ++x) f(size_t(y) * size_t(cells[0]) + size_t(x));
  };
  for (uint32_t t : active) for_cells(t, [&](size_t c) { ++start[c + 1]; });
  for (size_t c = 0; c < cell_count; ++c) start[c + 1] += start[c];
  std::vector<uint32_t> bucket(start.back());
  std::vector<size_t> fill(start.begin(), start.end() - 1);
  for (uint32_t t : active) for_cells(t, [&](size_t c) { bucket[fill[c]++] = t; });

  for (size_t c = 0; c < cell_count; ++c)
    for (size_t i = start[c]; i < start[c + 1]; ++i)
      for (size_t j = i + 1; j < start[c + 1]; ++j) {
        const uint32_t s = bucket[i], t = bucket[j];
        const Box &p = box[s], &q = box[t];
        // Boxes that only touch cannot hold interiors that overlap.
        const double lo[2] = {std::max(p.lo[0], q.lo[0]), std::max(p.lo[1], q.lo[1])};
        if (!(lo[0] < std::min(p.hi[0], q.hi[0]) && lo[1] < std::min(p.hi[1], q.hi[1]))) continue;
        if (size_t(cell_of(lo[1], 1)) * size_t(cells[0]) + size_t(cell_of(lo[0], 0)) != c) continue;  // tested elsewhere
        if (triangles_overlap(corner(s, 0), corner(s, 1), corner(s, 2), corner(t, 0), corner(t, 1), corner(t, 2)))
          pairs.push_back({s, t});
      }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

std::vector<TrianglePair> find_new_overlaps(const double* before, const double* after, const uint32_t* triangles,
                                            size_t triangle_count) {
  std::vector<TrianglePair> pairs = find_overlaps(after, triangles, triangle_count);
  auto corner = [&](const double* points, uint32_t t, int k) { return &points[2 * size_t(triangles[3 * size_t(t) + size_t(k)])]; };
  pairs.erase(std::remove_if(pairs.begin(), pairs.end(),
                             [&](const TrianglePair& p) {
                               return triangles_overlap(corner(before, p[0], 0), corner(before, p[0], 1),
                                                        corner(before, p[0], 2), corner(before, p[1], 0),
                                                        corner(before, p[1], 1), corner(before, p[1], 2));
                             }),
              pairs.end());
  return pairs;
}

}  // namespace uvpress::atlas
