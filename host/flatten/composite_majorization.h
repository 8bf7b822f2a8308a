// Composite majorization, Shtengel, Poranne, Sorkine-Hornung, Kovalsky, Lipman 2017, for
// the symmetric Dirichlet energy. Write J z = alpha z + beta conj(z) (similarity and
// anti-similarity parts); then sigma = s1 + s2, tau = s1 - s2 with s1 = |alpha|,
// s2 = |beta| (both convex in J), and D = h(s1, s2),
//   h = 1/4 (sigma^2 + sigma^-2 + tau^2 + tau^-2).
// The convex majorizer's Hessian is
//   grad g^T [Hess h]^+ grad g + [dh/ds1]^+ Hess s1 + [dh/ds2]^+ Hess s2.
// For this h, Hess h is already positive definite (eigenvalues 1 + 3 sigma^-4 and
// 1 + 3 tau^-4 along (1,1) and (1,-1)) and dh/ds2 >= 0, so only the alpha term can be
// dropped (when dh/ds1 < 0, i.e. the triangle is shrunk), as in the authors' code. Where
// h1 >= 0 this is the exact Hessian of D: CM is Newton's method with a PSD correction.
#pragma once

namespace uvpress::flatten {

// 4x4 CM Hessian proxy in vec(J) = (J00 J01 J10 J11). J must have det > 0.
void cm_hessian(const double J[4], double K[16]);

}  // namespace uvpress::flatten
