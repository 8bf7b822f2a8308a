// The engine's threading helper: the CPU kernels run on it, and so do the Vulkan backend's
// host fallbacks (cpu/ is the reference for both).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

namespace uvpress::engine {

// Runs fn(i) for i in [0, n) on up to `threads` threads, handing out blocks of `block` from
// an atomic counter (view costs vary a lot: balancing matters; 8 amortizes the counter over
// small views, 1 spreads a few large images over every thread). Results depend only on i,
// never on which thread ran it, so output is identical for any thread count.
template <class Fn>
void parallel_for(uint32_t n, unsigned threads, Fn fn, uint32_t block = 8) {
  unsigned t = std::max(1u, std::min<unsigned>(threads, (n + block - 1) / block));
  if (t == 1) {
    for (uint32_t i = 0; i < n; ++i) fn(i);
    return;
  }
  std::atomic<uint32_t> next{0};
  auto work = [&] {
    for (uint32_t first; (first = next.fetch_add(block)) < n;)
      for (uint32_t i = first; i < std::min(n, first + block); ++i) fn(i);
  };
  std::vector<std::thread> pool;
  for (unsigned k = 1; k < t; ++k) pool.emplace_back(work);
  work();
  for (auto& th : pool) th.join();
}

}  // namespace uvpress::engine
