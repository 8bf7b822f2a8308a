#include "flatten/composite_majorization.h"

#include <cmath>

namespace uvpress::flatten {

void cm_hessian(const double J[4], double K[16]) {
  // alpha = A_a vec(J), beta = A_b vec(J), rows of A as 4-vectors (each row has norm^2 1/2).
  static const double Aa[2][4] = {{0.5, 0, 0, 0.5}, {0, -0.5, 0.5, 0}};
  static const double Ab[2][4] = {{0.5, 0, 0, -0.5}, {0, 0.5, 0.5, 0}};
  const double a[2] = {0.5 * (J[0] + J[3]), 0.5 * (J[2] - J[1])};
  const double b[2] = {0.5 * (J[0] - J[3]), 0.5 * (J[1] + J[2])};
  const double s1 = std::hypot(a[0], a[1]), s2 = std::hypot(b[0], b[1]);
  const double sig = s1 + s2, tau = s1 - s2;
  // Unit directions; at beta = 0 any direction gives the same result (the beta block
  // becomes isotropic), so pick (1, 0).
  const double ah[2] = {a[0] / s1, a[1] / s1};
  double bu[2] = {1, 0};
  if (s2 > 0) bu[0] = b[0] / s2, bu[1] = b[1] / s2;
  const double is4 = 1 / (sig * sig * sig * sig), it4 = 1 / (tau * tau * tau * tau);
  const double h1 = 0.5 * (sig - 1 / (sig * sig * sig)) + 0.5 * (tau - 1 / (tau * tau * tau));
  // h2 / s2 in closed form, stable as s2 -> 0: 1 + (sig^2 + sig tau + tau^2) / (sig tau)^3.
  const double st = sig * tau;
  const double h2_over_s2 = 1 + (sig * sig + st + tau * tau) / (st * st * st);
  const double h11 = 1 + 1.5 * (is4 + it4), h12 = 1.5 * (is4 - it4);
  // Gradients of s1, s2 in vec(J): g1 = A_a^T ah, g2 = A_b^T bu.
  double g1[4], g2[4], pa[4], pb[4];  // pa, pb: A^T of the perpendicular directions
  const double ap[2] = {-ah[1], ah[0]}, bp[2] = {-bu[1], bu[0]};
  for (int i = 0; i < 4; ++i) {
    g1[i] = Aa[0][i] * ah[0] + Aa[1][i] * ah[1];
    g2[i] = Ab[0][i] * bu[0] + Ab[1][i] * bu[1];
    pa[i] = Aa[0][i] * ap[0] + Aa[1][i] * ap[1];
    pb[i] = Ab[0][i] * bp[0] + Ab[1][i] * bp[1];
  }
  // Hess s1 = A_a^T (I - ah ah^T) A_a / s1 = pa pa^T / s1; likewise Hess s2 = pb pb^T / s2,
  // and [h2] Hess s2 = (h2 / s2) pb pb^T.
  const double ca = h1 > 0 ? h1 / s1 : 0.0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      K[4 * i + j] = h11 * (g1[i] * g1[j] + g2[i] * g2[j]) + h12 * (g1[i] * g2[j] + g2[i] * g1[j]) +
                     ca * pa[i] * pa[j] + h2_over_s2 * pb[i] * pb[j];
}

}  // namespace uvpress::flatten
