// Per-triangle energies of the Jacobian and their chain rule to the three UV vertices,
// shared by flatten's solvers and the mesh stage.
//
// The symmetric Dirichlet distortion of Smith & Schaefer 2015 (Liu et al. 2018, eq. 2-3):
//   D(J) = 1/4 (|J|_F^2 + |J^-1|_F^2) = 1/4 (sigma^2 + sigma^-2 + tau^2 + tau^-2), det J > 0,
// and +inf otherwise; its minimum 1 is reached exactly by rotations.
//
// Jacobians (eq. 1, J = P * Rinv) and the 2x2 algebra come from core/mat2.h, on the same
// flat arrays: 4 doubles per 2x2 matrix, row-major (a b / c d), 2 doubles per UV vertex.
// A triangle's local dofs are (u0 v0 u1 v1 u2 v2); its 6x6 Hessian is stored as the 21
// entries of its lower triangle, row-major (hess21_index), the layout SparseSystem assembles.
#pragma once

#include "core/mat2.h"

#include <limits>

namespace uvpress::solve {

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

// Index of entry (a, b), a >= b, of a 6x6 lower triangle stored row-major in 21 doubles.
constexpr int hess21_index(int a, int b) { return a * (a + 1) / 2 + b; }

// Local 6x6 Hessian from a 4x4 Hessian K in vec(J) = (J00 J01 J10 J11) and Rinv:
// H[(m,r),(n,s)] = sum_jk c[m][j] K[(r,j),(s,k)] c[n][k], scaled by w. Writes 21 entries.
inline void local_hessian(const double* Rinv, const double K[16], double w, double h[21]) {
  const double c[3][2] = {{-(Rinv[0] + Rinv[2]), -(Rinv[1] + Rinv[3])}, {Rinv[0], Rinv[1]}, {Rinv[2], Rinv[3]}};
  // T[(r,j)][(n,s)] = sum_k K[(r,j),(s,k)] c[n][k]
  double T[4][6];
  for (int rj = 0; rj < 4; ++rj)
    for (int n = 0; n < 3; ++n)
      for (int s = 0; s < 2; ++s) T[rj][2 * n + s] = K[4 * rj + 2 * s] * c[n][0] + K[4 * rj + 2 * s + 1] * c[n][1];
  for (int a = 0; a < 6; ++a) {
    const int m = a / 2, r = a % 2;
    for (int b = 0; b <= a; ++b) h[hess21_index(a, b)] = w * (c[m][0] * T[2 * r][b] + c[m][1] * T[2 * r + 1][b]);
  }
}

}  // namespace uvpress::solve
