#include "flatten/problem.h"

#include "flatten/flatten.h"

#include <algorithm>
#include <cmath>

namespace uvpress::flatten {

Problem make_problem(const std::vector<double>& positions, const std::vector<uint32_t>& triangles) {
  Problem p;
  p.vertex_count = positions.size() / 3;
  p.triangles = triangles;
  const size_t nt = p.triangle_count();
  p.ideal.resize(4 * nt);
  p.area.resize(nt);
  std::vector<uint8_t> degenerate(nt, 0);
  std::vector<double> e1n(nt), e2x(nt), e2y(nt);  // triangle in its own frame: (0,0) (e1n,0) (e2x,e2y)
  for (size_t t = 0; t < nt; ++t) {
    const double* a = &positions[3 * size_t(triangles[3 * t])];
    const double* b = &positions[3 * size_t(triangles[3 * t + 1])];
    const double* c = &positions[3 * size_t(triangles[3 * t + 2])];
    double e1[3], e2[3], e3[3];
    for (int k = 0; k < 3; ++k) e1[k] = b[k] - a[k], e2[k] = c[k] - a[k], e3[k] = c[k] - b[k];
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const double twice_area = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const double l1 = std::sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    const double l2sq = e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2];
    const double l3sq = e3[0] * e3[0] + e3[1] * e3[1] + e3[2] * e3[2];
    const double longest = std::max({l1 * l1, l2sq, l3sq});
    p.area[t] = 0.5 * twice_area;
    if (!(twice_area > 1e-10 * longest) || !(l1 > 0)) {
      degenerate[t] = 1;
      continue;
    }
    e1n[t] = l1;
    e2x[t] = (e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2]) / l1;
    e2y[t] = twice_area / l1;
  }
  double total = 0;
  for (double a : p.area) total += a;
  if (!(total > 0) || !std::isfinite(total)) throw FlattenError("the mesh has zero area");
  p.scale = 1 / std::sqrt(total);
  const double mean = 1.0 / double(nt);  // mean area after scaling
  for (size_t t = 0; t < nt; ++t) {
    p.area[t] /= total;
    double* R = &p.ideal[4 * t];
    double x1, x2, y2;
    if (degenerate[t]) {
      ++p.degenerate;
      const double side = std::sqrt(4 * mean / std::sqrt(3.0));  // equilateral of the mean area
      x1 = side, x2 = 0.5 * side, y2 = 0.5 * std::sqrt(3.0) * side;
    } else {
      x1 = e1n[t] * p.scale, x2 = e2x[t] * p.scale, y2 = e2y[t] * p.scale;
    }
    // Reference edges (x1 0 / x2 y2) as columns: [[x1, x2], [0, y2]]; its inverse:
    R[0] = 1 / x1, R[1] = -x2 / (x1 * y2), R[2] = 0, R[3] = 1 / y2;
  }
  return p;
}

std::vector<double> area_weights(const Problem& p) {
  const double floor = 1e-6 / double(p.triangle_count());
  std::vector<double> w(p.area.size());
  for (size_t t = 0; t < w.size(); ++t) w[t] = std::max(p.area[t], floor);
  return w;
}

}  // namespace uvpress::flatten
