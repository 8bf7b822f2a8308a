// 2x2 linear algebra and triangle Jacobians, shared by flatten and the mesh stage (both
// fit per-triangle Jacobians). Flat arrays: 4 doubles per 2x2 matrix, row-major (a b / c d),
// and 2 doubles per vertex for UVs (u v interleaved).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

namespace uvpress {

// C = A B; C may alias A or B.
inline void mul(const double* A, const double* B, double* C) {
  const double c0 = A[0] * B[0] + A[1] * B[2], c1 = A[0] * B[1] + A[1] * B[3];
  const double c2 = A[2] * B[0] + A[3] * B[2], c3 = A[2] * B[1] + A[3] * B[3];
  C[0] = c0, C[1] = c1, C[2] = c2, C[3] = c3;
}

// |A - B|_F^2.
inline double dist2(const double* A, const double* B) {
  const double a = A[0] - B[0], b = A[1] - B[1], c = A[2] - B[2], d = A[3] - B[3];
  return a * a + b * b + c * c + d * d;
}

inline double det(const double* A) { return A[0] * A[3] - A[1] * A[2]; }

// Closest rotation to M (maximizes tr(R^T M)); the identity when M has no rotational part.
inline void polar(const double* M, double* R) {
  const double c = M[0] + M[3], s = M[2] - M[1], n = std::hypot(c, s);
  if (!(n > 0) || !std::isfinite(n)) {
    R[0] = 1, R[1] = 0, R[2] = 0, R[3] = 1;
    return;
  }
  R[0] = c / n, R[1] = -s / n, R[2] = s / n, R[3] = c / n;
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

// The Jacobian of triangle t = (i0, i1, i2) of `uv` (Smith & Schaefer 2015, eq. 1):
// J = P * Rinv, where P = [x1-x0, x2-x0] holds the UV edges as columns (row 0: u, row 1: v)
// and Rinv is the inverse of the reference edge matrix.
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

}  // namespace uvpress
