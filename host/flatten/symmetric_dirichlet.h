// The symmetric Dirichlet distortion of Smith & Schaefer 2015, paper eq. (2)-(3):
//   D(J) = 1/4 (|J|_F^2 + |J^-1|_F^2) = 1/4 (sigma^2 + sigma^-2 + tau^2 + tau^-2), det J > 0,
// and +inf otherwise; its minimum 1 is reached exactly by rotations.
//
// Jacobians (eq. 1, J = P * Rinv) and the 2x2 algebra come from core/mat2.h, on the same
// flat arrays: 4 doubles per 2x2 matrix, row-major (a b / c d), 2 doubles per UV vertex.
#pragma once

#include "core/mat2.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace uvpress::flatten {

// The fixed part of problems (4) and (5): connectivity and the ideal reference triangles.
struct Problem {
  size_t vertex_count = 0;
  std::vector<uint32_t> triangles;  // 3 per triangle
  std::vector<double> ideal;        // 4 per triangle: Rinv of the 3-D triangle in its own frame
  std::vector<double> area;         // per triangle, mesh scaled to total area 1 (so E/|M| = E)
  double scale = 1;                 // 3-D lengths were multiplied by this to reach area 1
  size_t degenerate = 0;            // triangles whose reference was replaced (see make_problem)
  size_t triangle_count() const { return triangles.size() / 3; }
};

// Builds the ideal references from 3-D positions (x y z per vertex) scaled to total area 1.
// A triangle with 2*area <= 1e-10 * (longest edge)^2 has no usable reference shape: it gets
// an equilateral reference of the mean triangle area and a weight floor (1e-6 of the mean
// area) in problem (5), so that its distortion is finite, it keeps a barrier against
// inversion, and it contributes (almost) nothing to E. No NaN can come out of it.
Problem make_problem(const std::vector<double>& positions, const std::vector<uint32_t>& triangles);

// Area weights of problem (5), with the floor above.
std::vector<double> area_weights(const Problem& p);

// D(J), eq. (2): 1/4 |J|^2 (1 + 1/det^2) for 2x2 J; +inf when det J <= 0.
inline double distortion(const double J[4]) {
  const double dj = det(J);
  if (!(dj > 0)) return std::numeric_limits<double>::infinity();
  const double f = J[0] * J[0] + J[1] * J[1] + J[2] * J[2] + J[3] * J[3];
  return 0.25 * f * (1 + 1 / (dj * dj));
}

// dD/dJ = 1/2 J (1 + 1/det^2) - 1/2 |J|^2 / det^3 * cof(J), cof(J) = (d -c / -b a).
inline void distortion_gradient(const double J[4], double G[4]) {
  const double dj = det(J);
  const double f = J[0] * J[0] + J[1] * J[1] + J[2] * J[2] + J[3] * J[3];
  const double a = 0.5 * (1 + 1 / (dj * dj)), b = -0.5 * f / (dj * dj * dj);
  G[0] = a * J[0] + b * J[3];
  G[1] = a * J[1] - b * J[2];
  G[2] = a * J[2] - b * J[1];
  G[3] = a * J[3] + b * J[0];
}

// Chain rule dE/dx for one triangle: dJ_rj/dx_{m,r} = c_{m,j}, c_1 = Rinv row 0,
// c_2 = Rinv row 1, c_0 = -(c_1 + c_2). Writes the 6 entries (u0 v0 u1 v1 u2 v2), scaled by w.
inline void triangle_gradient(const double* Rinv, const double G[4], double w, double g[6]) {
  const double c[3][2] = {{-(Rinv[0] + Rinv[2]), -(Rinv[1] + Rinv[3])}, {Rinv[0], Rinv[1]}, {Rinv[2], Rinv[3]}};
  for (int m = 0; m < 3; ++m)
    for (int r = 0; r < 2; ++r) g[2 * m + r] = w * (G[2 * r] * c[m][0] + G[2 * r + 1] * c[m][1]);
}

// Per-triangle loops run on OpenMP threads (static schedule) only from this size on:
// below it a pass takes well under a millisecond, and idle OpenMP threads that spin
// (libgomp's default wait policy) steal cores from CHOLMOD/OpenBLAS on small machines.
constexpr long kParallelMin = 50000;
inline bool worth_threads(long n) { return n >= kParallelMin; }

// Sum of f(i) for i in [0, n), in fixed blocks: the same bits whatever the thread count.
double fixed_order_sum(size_t n, const double* values);

}  // namespace uvpress::flatten
