// Quantiles of a sample, for reports and benchmarks.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace uvpress {

// The q-quantile (q in [0, 1]) of `v` by nearest rank on the sorted sample; 0 when empty.
inline double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const double rank = std::floor(std::clamp(q, 0.0, 1.0) * double(v.size() - 1) + 0.5);
  return v[size_t(rank)];
}

}  // namespace uvpress
