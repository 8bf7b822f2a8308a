// Progressive reference triangles, paper §3.3, eq. (6)-(10). Given the Jacobian
// J_i = U S V^T of a triangle relative to its ideal (3-D) reference, the interpolated
// Jacobian J_i(t) = U S^t V^T (eq. 7) has distortion D(J_i(t)) increasing in t (eq. 8).
// Each triangle with D > K gets t_i solving D(J_i(t_i)) = K (eq. 9) by Newton-Raphson;
// t_com = min_i t_i (eq. 10), 1 when no triangle exceeds K. The new reference is
// f_i^r = J_i(t_com)^-1 f_i^p (eq. 6); in Rinv form Rinv_i^r = Rinv_i V S^(t-1) V^T, so
// that the triangle's Jacobian relative to it is exactly J_i(t_com) at this iterate.
#pragma once

#include <cstddef>
#include <vector>

namespace uvpress::flatten {

// Eq. (9) for one triangle with singular values s1, s2 (> 0): the t in (0, 1] with
// 1/4 (s1^2t + s1^-2t + s2^2t + s2^-2t) = K; 1 when D(J) <= K already. Newton-Raphson from
// the right of the root (the function is convex and increasing in t), residual < 1e-5
// as in the authors' code, started from min(1, the root of the dominant term) so that huge
// or tiny singular values cannot overflow.
double triangle_parameter(double s1, double s2, double K);

// t_com of eq. (10) over the Jacobians `J` (4 per triangle, relative to the ideal
// references) whose distortions `D` are given. Deterministic (min).
double common_parameter(const std::vector<double>& J, const std::vector<double>& D, double K);

// Rinv of the progressive references for parameter t (eq. 6-7), from the ideal Rinv and J.
void progressive_references(const std::vector<double>& ideal, const std::vector<double>& J, double t,
                            std::vector<double>& ref);

}  // namespace uvpress::flatten
