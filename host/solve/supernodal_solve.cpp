// The float supernodal factor and its subtree-parallel triangular solves
// (supernodal_solve.h). How:
//
// A CHOLMOD supernode s holds columns super[s] .. super[s+1]-1 of L, dense, column-major,
// nrows x ncols with leading dimension nrows; its row indices are s_[pi[s] ..], the first
// ncols of them its own columns. The supernodes are in a topological order of their
// elimination tree (a parent's index is larger), and postordered, so every subtree is a
// contiguous index range. The parent of s is the supernode holding its first off-diagonal
// row; every off-diagonal row of s lies in an ancestor of s.
//
// Split: starting from the roots, the subtree with the most entries is cut off at its root
// (which moves to the top) until the subtrees, binned into kGroups groups by decreasing size,
// are balanced; of the splits tried, the one with the least top + largest group is kept.
// Forward solve: the groups in parallel (updates of top columns into the group's buffer),
// the buffers into y in group order, then the top. Backward: the top, then the groups.
#include "solve/supernodal_solve.h"

#include "solve/supernode_kernels.h"

#include <algorithm>
#include <cstddef>
#include <omp.h>

namespace uvpress::solve {

namespace {
// Groups of subtrees: fixed, not the thread count (determinism, see the header). Four
// groups keep two threads busy when the tree splits unevenly and leave room for four.
constexpr int kGroups = 4;
// Splits tried at most: each moves one separator to the top.
constexpr int kMaxSplits = 256;
// Subtrees below this many entries are not worth a group's overhead: no split at all.
constexpr int64_t kMinParallelEntries = 1 << 18;
}  // namespace

void FloatSupernodalFactor::analyze(const cholmod_factor& L) {
  n_ = int(L.n);
  nsuper_ = int(L.nsuper);
  const int* super = static_cast<const int*>(L.super);
  const int* pi = static_cast<const int*>(L.pi);
  const int* px = static_cast<const int*>(L.px);
  const int* s = static_cast<const int*>(L.s);
  const int* perm = static_cast<const int*>(L.Perm);
  super_.assign(super, super + nsuper_ + 1);
  pi_.assign(pi, pi + nsuper_ + 1);
  px_.assign(px, px + nsuper_ + 1);
  s_.assign(s, s + pi_[size_t(nsuper_)]);
  perm_.assign(perm, perm + n_);
  assigned_ = false;

  // Tree, entries per supernode and per subtree, subtree index ranges.
  const size_t ns = size_t(nsuper_);
  std::vector<int> column_super(size_t(n_), 0), parent(ns, -1), first(ns, 0), count(ns, 1);
  std::vector<int64_t> own(ns, 0), below(ns, 0);
  std::vector<std::vector<int>> children(ns);
  std::vector<int> roots;
  bool postordered = true;
  int64_t total = 0;
  for (int k = 0; k < nsuper_; ++k)
    for (int c = super_[size_t(k)]; c < super_[size_t(k) + 1]; ++c) column_super[size_t(c)] = k;
  for (int k = 0; k < nsuper_; ++k) {
    const int ncols = super_[size_t(k) + 1] - super_[size_t(k)], nrows = pi_[size_t(k) + 1] - pi_[size_t(k)];
    own[size_t(k)] = int64_t(nrows) * ncols;
    total += own[size_t(k)];
    first[size_t(k)] = k;
    if (nrows > ncols) {
      parent[size_t(k)] = column_super[size_t(s_[size_t(pi_[size_t(k)] + ncols)])];
      postordered &= parent[size_t(k)] > k;
    }
  }
  for (int k = 0; k < nsuper_ && postordered; ++k) {
    below[size_t(k)] += own[size_t(k)];
    if (const int p = parent[size_t(k)]; p >= 0) {
      below[size_t(p)] += below[size_t(k)];
      count[size_t(p)] += count[size_t(k)];
      first[size_t(p)] = std::min(first[size_t(p)], first[size_t(k)]);
      children[size_t(p)].push_back(k);
    } else {
      roots.push_back(k);
    }
  }
  for (int k = 0; k < nsuper_ && postordered; ++k) postordered = k - first[size_t(k)] + 1 == count[size_t(k)];

  // Split (see the top of the file). cost = top entries + the largest group's.
  group_start_.assign(1, 0);
  ranges_.clear();
  top_.clear();
  std::vector<int> best_top, best_subtrees;
  std::vector<int> top, subtrees = roots;
  auto bins = [&](std::vector<int>& trees, std::vector<int>* assignment) {
    std::sort(trees.begin(), trees.end(), [&](int a, int b) {
      return below[size_t(a)] != below[size_t(b)] ? below[size_t(a)] > below[size_t(b)] : a < b;
    });
    int64_t load[kGroups] = {};
    if (assignment) assignment->assign(trees.size(), 0);
    for (size_t i = 0; i < trees.size(); ++i) {
      const int g = int(std::min_element(load, load + kGroups) - load);
      load[g] += below[size_t(trees[i])];
      if (assignment) (*assignment)[i] = g;
    }
    return *std::max_element(load, load + kGroups);
  };
  int64_t top_entries = 0, best_cost = total + 1;
  if (postordered && total >= kMinParallelEntries) {
    for (int split = 0; split <= kMaxSplits && !subtrees.empty(); ++split) {
      const int64_t cost = top_entries + bins(subtrees, nullptr);
      if (cost < best_cost) best_cost = cost, best_top = top, best_subtrees = subtrees;
      const int heaviest = subtrees.front();  // sorted by bins()
      if (children[size_t(heaviest)].empty()) break;
      subtrees.erase(subtrees.begin());
      top.push_back(heaviest);
      top_entries += own[size_t(heaviest)];
      for (int c : children[size_t(heaviest)]) subtrees.push_back(c);
    }
  }
  if (best_cost > total) {  // serial: everything is the top, no groups
    for (int k = 0; k < nsuper_; ++k) top_.push_back(k);
  } else {
    std::vector<int> assignment;
    bins(best_subtrees, &assignment);
    for (int g = 0; g < kGroups; ++g) {
      std::vector<std::pair<int, int>> mine;
      for (size_t i = 0; i < best_subtrees.size(); ++i)
        if (assignment[i] == g) mine.emplace_back(first[size_t(best_subtrees[i])], best_subtrees[i]);
      std::sort(mine.begin(), mine.end());
      ranges_.insert(ranges_.end(), mine.begin(), mine.end());
      group_start_.push_back(int(ranges_.size()));
    }
    std::vector<uint8_t> in_range(size_t(nsuper_), 0);
    for (auto [a, b] : ranges_)
      for (int k = a; k <= b; ++k) in_range[size_t(k)] = 1;
    for (int k = 0; k < nsuper_; ++k)
      if (!in_range[size_t(k)]) top_.push_back(k);
  }
  top_slot_.assign(size_t(n_), -1);
  top_columns_ = 0;
  int64_t top_total = 0;
  for (int k : top_) {
    top_total += own[size_t(k)];
    for (int c = super_[size_t(k)]; c < super_[size_t(k) + 1]; ++c) top_slot_[size_t(c)] = top_columns_++;
  }
  top_share_ = total > 0 ? double(top_total) / double(total) : 1.0;
  y_.assign(size_t(n_), 0.0);
  buffers_.assign(size_t(groups()) * size_t(top_columns_), 0.0);
}

void FloatSupernodalFactor::assign(const cholmod_factor& L) {
  const double* x = static_cast<const double*>(L.x);
  const long size = long(px_[size_t(nsuper_)]);
  x_.resize(size_t(size));
#pragma omp parallel for schedule(static) if (size >= (1 << 20))
  for (long i = 0; i < size; ++i) x_[size_t(i)] = float(x[i]);
  assigned_ = true;
}

// L y = b for supernode s: y's own columns solved, off-diagonal rows updated (into
// top_buffer for top columns when given).
void FloatSupernodalFactor::forward(int s, double* y, double* top_buffer) {
  const int c0 = super_[size_t(s)], ncols = super_[size_t(s) + 1] - c0;
  const int m = pi_[size_t(s) + 1] - pi_[size_t(s)];
  const int* rows = &s_[size_t(pi_[size_t(s)])];
  double* w = scratch_[size_t(omp_get_thread_num())].data();
  for (int i = 0; i < ncols; ++i) w[i] = y[c0 + i];
  for (int i = ncols; i < m; ++i) w[i] = 0;
  supernode_forward(&x_[size_t(px_[size_t(s)])], m, ncols, w);
  for (int i = 0; i < ncols; ++i) y[c0 + i] = w[i];
  for (int i = ncols; i < m; ++i) {
    const int r = rows[i];
    const int slot = top_buffer ? top_slot_[size_t(r)] : -1;
    if (slot >= 0) top_buffer[slot] += w[i];
    else y[r] += w[i];
  }
}

// L' x = y for supernode s, its ancestors' x already in y.
void FloatSupernodalFactor::backward(int s, double* y) {
  const int c0 = super_[size_t(s)], ncols = super_[size_t(s) + 1] - c0;
  const int m = pi_[size_t(s) + 1] - pi_[size_t(s)];
  const int* rows = &s_[size_t(pi_[size_t(s)])];
  double* w = scratch_[size_t(omp_get_thread_num())].data();
  for (int i = 0; i < ncols; ++i) w[i] = y[c0 + i];
  for (int i = ncols; i < m; ++i) w[i] = y[rows[i]];
  supernode_backward(&x_[size_t(px_[size_t(s)])], m, ncols, w);
  for (int i = 0; i < ncols; ++i) y[c0 + i] = w[i];
}

void FloatSupernodalFactor::solve(const double* r, double* z) {
  int max_rows = 0;
  for (int k = 0; k < nsuper_; ++k) max_rows = std::max(max_rows, pi_[size_t(k) + 1] - pi_[size_t(k)]);
  scratch_.resize(size_t(std::max(1, omp_get_max_threads())));
  for (auto& w : scratch_) w.resize(size_t(max_rows));
  double* y = y_.data();
  for (int i = 0; i < n_; ++i) y[i] = r[perm_[size_t(i)]];

  const int ng = groups();
  std::fill(buffers_.begin(), buffers_.end(), 0.0);
#pragma omp parallel for schedule(static) if (ng > 1)
  for (int g = 0; g < ng; ++g)
    for (int q = group_start_[size_t(g)]; q < group_start_[size_t(g) + 1]; ++q)
      for (int k = ranges_[size_t(q)].first; k <= ranges_[size_t(q)].second; ++k)
        forward(k, y, &buffers_[size_t(g) * size_t(top_columns_)]);
  if (ng > 0)  // the groups' updates of the top, in group order
    for (int k : top_)
      for (int c = super_[size_t(k)]; c < super_[size_t(k) + 1]; ++c)
        for (int g = 0; g < ng; ++g) y[c] += buffers_[size_t(g) * size_t(top_columns_) + size_t(top_slot_[size_t(c)])];
  for (int k : top_) forward(k, y, nullptr);

  for (auto it = top_.rbegin(); it != top_.rend(); ++it) backward(*it, y);
#pragma omp parallel for schedule(static) if (ng > 1)
  for (int g = 0; g < ng; ++g)
    for (int q = group_start_[size_t(g) + 1] - 1; q >= group_start_[size_t(g)]; --q)
      for (int k = ranges_[size_t(q)].second; k >= ranges_[size_t(q)].first; --k) backward(k, y);

  for (int i = 0; i < n_; ++i) z[perm_[size_t(i)]] = y[i];
}

}  // namespace uvpress::solve
