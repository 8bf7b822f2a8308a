#include "flatten/slim.h"

#include "core/mat2.h"

namespace uvpress::flatten {

void slim_hessian(const double J[4], double K[16]) {
  const Svd2 s = svd2(J);
  auto weight2 = [](double x) {  // w^2, with x > 0 (feasible iterates only)
    const double i = 1 / x;
    return 0.25 * (1 + i + i * i + i * i * i);
  };
  const double w1 = weight2(s.s1), w2 = weight2(s.s2);
  // M = W^T W = U diag(w1, w2) U^T, U = rotation by phi.
  const double c = s.cu, sn = s.su;
  const double m00 = w1 * c * c + w2 * sn * sn, m11 = w1 * sn * sn + w2 * c * c, m01 = (w1 - w2) * c * sn;
  // K[(r,j),(s,k)] = 2 M[r][s] delta_jk
  const double M[2][2] = {{m00, m01}, {m01, m11}};
  for (int r = 0; r < 2; ++r)
    for (int j = 0; j < 2; ++j)
      for (int s2 = 0; s2 < 2; ++s2)
        for (int k = 0; k < 2; ++k) K[4 * (2 * r + j) + 2 * s2 + k] = j == k ? 2 * M[r][s2] : 0.0;
}

}  // namespace uvpress::flatten
