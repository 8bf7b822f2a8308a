#include "solve/line_search.h"

#include "core/parallel.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace uvpress::solve {

namespace {

// Smallest positive root of a x^2 + b x + c (c > 0: the triangle is valid at x = 0).
double smallest_positive_root(double a, double b, double c) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  const double scale = std::max({std::abs(a), std::abs(b), std::abs(c)});
  if (!(scale > 0)) return inf;
  if (std::abs(a) <= 1e-14 * scale) {  // linear
    return b < 0 ? -c / b : inf;
  }
  const double disc = b * b - 4 * a * c;
  if (disc < 0) return inf;
  const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
  double r1 = q / a, r2 = q != 0 ? c / q : inf;
  double best = inf;
  if (r1 > 0) best = std::min(best, r1);
  if (r2 > 0) best = std::min(best, r2);
  return best;
}

}  // namespace

double max_injective_step(const std::vector<uint32_t>& tris, const std::vector<double>& uv,
                          const std::vector<double>& d) {
  const long nt = long(tris.size() / 3);
  double best = std::numeric_limits<double>::infinity();
#pragma omp parallel for schedule(static) if (worth_threads(nt)) reduction(min : best)
  for (long t = 0; t < nt; ++t) {
    const uint32_t* v = &tris[3 * size_t(t)];
    const size_t i0 = 2 * size_t(v[0]), i1 = 2 * size_t(v[1]), i2 = 2 * size_t(v[2]);
    const double p00 = uv[i1] - uv[i0], p01 = uv[i2] - uv[i0], p10 = uv[i1 + 1] - uv[i0 + 1], p11 = uv[i2 + 1] - uv[i0 + 1];
    const double d00 = d[i1] - d[i0], d01 = d[i2] - d[i0], d10 = d[i1 + 1] - d[i0 + 1], d11 = d[i2 + 1] - d[i0 + 1];
    const double a = d00 * d11 - d01 * d10;
    const double b = p00 * d11 + d00 * p11 - p01 * d10 - d01 * p10;
    const double c = p00 * p11 - p01 * p10;
    best = std::min(best, smallest_positive_root(a, b, c));
  }
  return best;  // min is exact: the same whatever the order
}

LineSearchResult armijo(std::vector<double>& uv, const std::vector<double>& d, double e0, double slope, double a0,
                        const std::function<double(const std::vector<double>&)>& energy) {
  constexpr double c = 0.2;
  std::vector<double> trial(uv.size());
  double a = a0;
  for (int k = 0; k < 60 && a > 0; ++k, a *= 0.5) {
    for (size_t i = 0; i < uv.size(); ++i) trial[i] = uv[i] + a * d[i];
    const double e = energy(trial);
    // e < e0 too: at the floating-point floor e0 + c a slope rounds to e0, and a step that
    // lowers nothing is no step (the caller then reports a stall, not a fake decrease).
    if (std::isfinite(e) && e < e0 && e <= e0 + c * a * slope) {
      uv.swap(trial);
      return {a, e};
    }
  }
  return {0, e0};
}

}  // namespace uvpress::solve
