// The engine's threading helper: the CPU kernels run on it, and so do the Vulkan backend's
// host fallbacks (cpu/ is the reference for both).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>

namespace uvpress::engine {

// Runs fn(i) for i in [0, n) on up to `threads` threads, handing out blocks of `block` from
// an atomic counter (view costs vary a lot: balancing matters; 8 amortizes the counter over
// small views, 1 spreads a few large images over every thread). Results depend only on i,
// never on which thread ran it, so output is identical for any thread count.
//
// The threads are OpenMP's, the host's pool (DESIGN: one threading library): threads of
// the engine's own beside it left both pools' threads competing for the cores, libgomp's
// waiting ones spinning (Fox's eval --flatten: 11 % of its samples in libgomp's spin).
// Inside an active OpenMP region (nested) the loop runs on the calling thread alone.
template <class Fn>
void parallel_for(uint32_t n, unsigned threads, Fn fn, uint32_t block = 8) {
  const unsigned t = std::max(1u, std::min<unsigned>(threads, (n + block - 1) / block));
  if (t == 1) {
    for (uint32_t i = 0; i < n; ++i) fn(i);
    return;
  }
  std::atomic<uint32_t> next{0};
#pragma omp parallel num_threads(t)
  for (uint32_t first; (first = next.fetch_add(block)) < n;)
    for (uint32_t i = first; i < std::min(n, first + block); ++i) fn(i);
}

}  // namespace uvpress::engine
