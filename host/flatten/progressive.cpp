#include "flatten/progressive.h"

#include "core/mat2.h"
#include "core/parallel.h"

#include <algorithm>
#include <cmath>

namespace uvpress::flatten {

double triangle_parameter(double s1, double s2, double K) {
  const double l1 = std::log(s1), l2 = std::log(s2);
  // D(t) = 1/2 (cosh(2 t l1) + cosh(2 t l2)), D'(t) = l1 sinh(2 t l1) + l2 sinh(2 t l2).
  auto D = [&](double t) { return 0.5 * (std::cosh(2 * t * l1) + std::cosh(2 * t * l2)); };
  if (!(D(1) > K)) return 1.0;
  const double big = std::max(std::abs(l1), std::abs(l2));
  // 1/4 exp(2 t big) <= D(t): the root of the dominant term lies right of the true root.
  double t = std::min(1.0, std::log(4 * K) / (2 * big));
  for (int k = 0; k < 100; ++k) {
    const double r = D(t) - K;
    if (std::abs(r) < 1e-5) break;
    const double dr = l1 * std::sinh(2 * t * l1) + l2 * std::sinh(2 * t * l2);
    if (!(dr > 0)) break;
    const double next = t - r / dr;
    if (!(next > 0) || !(next < t)) break;  // monotone from the right; stop on round-off
    t = next;
  }
  return t;
}

double common_parameter(const std::vector<double>& J, const std::vector<double>& D, double K) {
  const long nt = long(D.size());
  double t = 1.0;
#pragma omp parallel for schedule(static) if (worth_threads(nt)) reduction(min : t)
  for (long i = 0; i < nt; ++i) {
    if (!(D[size_t(i)] > K)) continue;
    const Svd2 s = svd2(&J[4 * size_t(i)]);
    t = std::min(t, triangle_parameter(s.s1, s.s2, K));
  }
  return t;
}

void progressive_references(const std::vector<double>& ideal, const std::vector<double>& J, double t,
                            std::vector<double>& ref) {
  const long nt = long(ideal.size() / 4);
  ref.resize(ideal.size());
#pragma omp parallel for schedule(static) if (worth_threads(nt))
  for (long i = 0; i < nt; ++i) {
    const double* R0 = &ideal[4 * size_t(i)];
    double* R = &ref[4 * size_t(i)];
    const Svd2 s = svd2(&J[4 * size_t(i)]);
    // M = V diag(s1^(t-1), s2^(t-1)) V^T, V = rotation by psi.
    const double a = std::pow(s.s1, t - 1), b = std::pow(s.s2, t - 1);
    const double c = s.cv, sn = s.sv;
    const double m00 = a * c * c + b * sn * sn, m11 = a * sn * sn + b * c * c, m01 = (a - b) * c * sn;
    R[0] = R0[0] * m00 + R0[1] * m01;
    R[1] = R0[0] * m01 + R0[1] * m11;
    R[2] = R0[2] * m00 + R0[3] * m01;
    R[3] = R0[2] * m01 + R0[3] * m11;
  }
}

}  // namespace uvpress::flatten
