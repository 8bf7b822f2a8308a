// Union-find with path halving; the smaller root wins a union, so component ids depend
// only on the input, never on the order of finds.
#pragma once

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

namespace uvpress {

struct DisjointSets {
  std::vector<uint32_t> parent;
  explicit DisjointSets(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  uint32_t find(uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

}  // namespace uvpress
