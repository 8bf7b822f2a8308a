// Host-side parallel helpers shared by the solvers: when a per-triangle loop is worth
// OpenMP threads, and a sum whose bits do not depend on the thread count.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace uvpress {

// Per-triangle loops run on OpenMP threads (static schedule) only from this size on:
// below it a pass takes well under a millisecond, and idle OpenMP threads that spin
// (libgomp's default wait policy) steal cores from CHOLMOD/OpenBLAS on small machines.
constexpr long kParallelMin = 50000;
inline bool worth_threads(long n) { return n >= kParallelMin; }

// Sum of values[0, n) in fixed blocks of 4096, the blocks' sums added in order: the same
// bits whatever the thread count.
inline double fixed_order_sum(size_t n, const double* values) {
  constexpr size_t kBlock = 4096;
  const size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<double> partial(blocks);
#pragma omp parallel for schedule(static) if (worth_threads(long(n)))
  for (long b = 0; b < long(blocks); ++b) {
    double s = 0;
    const size_t end = std::min(n, size_t(b + 1) * kBlock);
    for (size_t i = size_t(b) * kBlock; i < end; ++i) s += values[i];
    partial[size_t(b)] = s;
  }
  double s = 0;
  for (double x : partial) s += x;
  return s;
}

}  // namespace uvpress
