#include "perceptual/rate_allocation.h"

#include <algorithm>
#include <cmath>

namespace uvpress::perceptual {

RateAllocation allocate_by_equal_slope(const LossCurves& curves, const std::vector<double>& area,
                                       const std::vector<double>& weight, double cost, double min_scale, size_t steps) {
  const size_t n = area.size(), k = curves.scales.size();
  RateAllocation out;
  out.scale.assign(n, 1.0);
  if (n == 0 || k == 0) return out;
  // The grid, and each triangle's loss on it: linear between measured scales, the smallest
  // measured scale's loss below it, then the running maximum from the top so that a
  // smaller scale never loses less (measurement noise must not buy texels back).
  steps = std::max<size_t>(steps, 2);
  std::vector<double> grid(steps);
  for (size_t i = 0; i < steps; ++i) grid[i] = min_scale * std::pow(1.0 / min_scale, double(i) / double(steps - 1));
  std::vector<double> g(n * steps);
  for (size_t t = 0; t < n; ++t) {
    const double* l = &curves.loss[t * k];
    for (size_t i = 0; i < steps; ++i) {
      const double s = grid[i];
      size_t j = 0;
      while (j + 1 < k && curves.scales[j + 1] < s) ++j;
      double v;
      if (s <= curves.scales[0]) v = l[0];
      else if (j + 1 >= k) v = l[k - 1];
      else v = l[j] + (l[j + 1] - l[j]) * (s - curves.scales[j]) / (curves.scales[j + 1] - curves.scales[j]);
      g[t * steps + i] = v;
    }
    for (size_t i = steps - 1; i-- > 0;) g[t * steps + i] = std::max(g[t * steps + i], g[t * steps + i + 1]);
  }
  double total = 0;
  for (double a : area) total += a;
  const double budget = std::clamp(cost, 0.0, 1.0) * total;
  std::vector<size_t> pick(n, steps - 1);
  auto spend = [&](double mu) {
    double s2 = 0;
    for (size_t t = 0; t < n; ++t) {
      size_t best = steps - 1;
      double best_f = weight[t] * g[t * steps + best] + mu * area[t] * grid[best] * grid[best];
      for (size_t i = steps - 1; i-- > 0;) {
        const double f = weight[t] * g[t * steps + i] + mu * area[t] * grid[i] * grid[i];
        if (f < best_f) best_f = f, best = i;  // ties keep the larger scale
      }
      pick[t] = best;
      s2 += area[t] * grid[best] * grid[best];
    }
    return s2;
  };
  // mu = 0 spends everything (every triangle at scale 1); bisect mu in log space for the
  // largest spend within the budget.
  double lo = 0, hi = 1e-12;
  if (spend(lo) <= budget) {
    out.multiplier = 0;
  } else {
    while (spend(hi) > budget && hi < 1e30) hi *= 10;
    for (int it = 0; it < 80; ++it) {
      const double mid = lo == 0 ? hi / 1e6 : std::sqrt(lo * hi);
      if (spend(mid) > budget) lo = mid;
      else hi = mid;
    }
    spend(hi);
    out.multiplier = hi;
  }
  double s2 = 0;
  for (size_t t = 0; t < n; ++t) out.scale[t] = grid[pick[t]], s2 += area[t] * grid[pick[t]] * grid[pick[t]];
  out.spent = total > 0 ? s2 / total : 0;
  return out;
}

}  // namespace uvpress::perceptual
