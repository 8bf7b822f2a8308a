// SLIM, Rabinovich, Poranne, Panozzo, Sorkine-Hornung 2017: the reweighted local/global
// proxy of the symmetric Dirichlet energy. Per triangle, with J = U diag(s) V^T and R = U V^T
// the closest rotation, the proxy is w |W (J - R)|_F^2 with W = U diag(w1, w2) U^T and
//   w_k^2 = D'(s_k) / (2 (s_k - 1)) = 1/4 (1 + 1/s + 1/s^2 + 1/s^3)
// (for D = 1/4 (s^2 + s^-2) per singular value; the authors' unnormalized energy gives
// sqrt(1 + 1/s + 1/s^2 + 1/s^3)). Its gradient equals grad D, so the global step
// "minimize the proxy" is the Newton-like step H_slim d = -grad E with H_slim the proxy's
// Hessian, the form the authors' code solves.
#pragma once

namespace uvpress::flatten {

// 4x4 Hessian of |W (J - R)|^2 in vec(J) = (J00 J01 J10 J11): 2 (W^T W) (x) I_2.
void slim_hessian(const double J[4], double K[16]);

}  // namespace uvpress::flatten
