// The symmetric Dirichlet distortion of Smith & Schaefer 2015, paper eq. (2)-(3):
//   D(J) = 1/4 (|J|_F^2 + |J^-1|_F^2) = 1/4 (sigma^2 + sigma^-2 + tau^2 + tau^-2), det J > 0,
// and +inf otherwise; its minimum 1 is reached exactly by rotations.
//
// A triangle's Jacobian (eq. 1) is J = P * Rinv, where P = [x1-x0, x2-x0] holds the UV
// edges as columns (row 0: u, row 1: v) and Rinv is the inverse of the reference edge
// matrix. Everything here works on flat arrays: 4 doubles per 2x2 matrix, row-major
// (a b / c d), and 2 doubles per vertex for UVs (u v interleaved).
#pragma once

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

// J = P * Rinv for triangle (i0, i1, i2) of `uv`.
inline void jacobian(const double* Rinv, const double* uv, const uint32_t* t, double J[4]) {
  const double* x0 = uv + 2 * size_t(t[0]);
  const double* x1 = uv + 2 * size_t(t[1]);
  const double* x2 = uv + 2 * size_t(t[2]);
  const double p00 = x1[0] - x0[0], p01 = x2[0] - x0[0], p10 = x1[1] - x0[1], p11 = x2[1] - x0[1];
  J[0] = p00 * Rinv[0] + p01 * Rinv[2];
  J[1] = p00 * Rinv[1] + p01 * Rinv[3];
  J[2] = p10 * Rinv[0] + p11 * Rinv[2];
  J[3] = p10 * Rinv[1] + p11 * Rinv[3];
}

// D(J), eq. (2): 1/4 |J|^2 (1 + 1/det^2) for 2x2 J; +inf when det J <= 0.
inline double distortion(const double J[4]) {
  const double det = J[0] * J[3] - J[1] * J[2];
  if (!(det > 0)) return std::numeric_limits<double>::infinity();
  const double f = J[0] * J[0] + J[1] * J[1] + J[2] * J[2] + J[3] * J[3];
  return 0.25 * f * (1 + 1 / (det * det));
}

// dD/dJ = 1/2 J (1 + 1/det^2) - 1/2 |J|^2 / det^3 * cof(J), cof(J) = (d -c / -b a).
inline void distortion_gradient(const double J[4], double G[4]) {
  const double det = J[0] * J[3] - J[1] * J[2];
  const double f = J[0] * J[0] + J[1] * J[1] + J[2] * J[2] + J[3] * J[3];
  const double a = 0.5 * (1 + 1 / (det * det)), b = -0.5 * f / (det * det * det);
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

// Closed-form SVD of a 2x2 matrix through its similarity / anti-similarity parts
// (J z = alpha z + beta conj(z) in complex notation): sigma1 = |alpha| + |beta|,
// sigma2 = |alpha| - |beta| (negative when det J < 0), U = R(phi), V = R(psi) with
// phi = (arg alpha + arg beta)/2, psi = (arg beta - arg alpha)/2.
struct Svd2 {
  double s1, s2;          // sigma >= tau (tau signed)
  double cu, su, cv, sv;  // cos/sin of phi and psi
};
inline Svd2 svd2(const double J[4]) {
  const double ar = 0.5 * (J[0] + J[3]), ai = 0.5 * (J[2] - J[1]);
  const double br = 0.5 * (J[0] - J[3]), bi = 0.5 * (J[1] + J[2]);
  const double na = std::hypot(ar, ai), nb = std::hypot(br, bi);
  const double ta = std::atan2(ai, ar), tb = std::atan2(bi, br);
  const double phi = 0.5 * (ta + tb), psi = 0.5 * (tb - ta);
  return {na + nb, na - nb, std::cos(phi), std::sin(phi), std::cos(psi), std::sin(psi)};
}

// Per-triangle loops run on OpenMP threads (static schedule) only from this size on:
// below it a pass takes well under a millisecond, and idle OpenMP threads that spin
// (libgomp's default wait policy) steal cores from CHOLMOD/OpenBLAS on small machines.
constexpr long kParallelMin = 50000;
inline bool worth_threads(long n) { return n >= kParallelMin; }

// Sum of f(i) for i in [0, n), in fixed blocks: the same bits whatever the thread count.
double fixed_order_sum(size_t n, const double* values);

}  // namespace uvpress::flatten
