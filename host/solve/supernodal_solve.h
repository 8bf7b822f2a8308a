// A single-precision copy of a CHOLMOD supernodal LL' factor, applied as (P' L L' P)^-1 by
// triangular solves that run independent subtrees of the supernodal elimination tree on
// separate OpenMP threads. It is the preconditioner of SparseSystem's PCG (an earlier
// factor preconditions the next system) where the system is not split (split_cholesky.h
// keeps float copies of its own): there a solve is the whole cost of an iteration,
// and a triangular solve with one right-hand side is bound by memory bandwidth, so half
// the bytes and two threads are what make it faster.
//
// Exactness: the float factor L~ is used by both the forward and the backward solve, so the
// preconditioner is exactly L~ L~', symmetric positive definite, within 2^-24 of the double
// factor entry by entry; PCG's theory holds for it unchanged. Vectors stay double.
//
// Determinism: the subtrees and their grouping depend on the factor's structure only (the
// tree and the entry counts), never on the thread count. Each group accumulates its updates
// of the top of the tree (the separators above every group) in a buffer of its own, and the
// buffers are added in group order, so the bits are the same for any OMP_NUM_THREADS.
#pragma once

#include <Eigen/CholmodSupport>
#include <Eigen/Sparse>

#include <cstdint>
#include <vector>

namespace uvpress::solve {

// Eigen's CHOLMOD supernodal LL' of a lower-stored matrix, its factor readable.
struct SupernodalLLT : Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> {
  const cholmod_factor& factor() const { return *m_cholmodFactor; }
};

class FloatSupernodalFactor {
 public:
  // Reads the structure of a supernodal LL' factor (int indices: CHOLMOD's cholmod_ API):
  // supernodes, their rows, the elimination tree, and the subtree groups. Once per symbolic
  // analysis; assign() then copies the values of each numeric factorization.
  void analyze(const cholmod_factor& L);
  // Copies L's values, rounded to float.
  void assign(const cholmod_factor& L);
  bool ready() const { return assigned_; }
  // z = P' L~^-T L~^-1 P r (r and z of size n, distinct).
  void solve(const double* r, double* z);

  // The structure's split: subtree groups and the share of the factor's entries above them.
  int groups() const { return int(group_start_.size()) - 1; }
  double top_share() const { return top_share_; }

 private:
  int n_ = 0, nsuper_ = 0;
  std::vector<int> super_, pi_, s_;  // CHOLMOD's supernode columns, row pointers, row indices
  std::vector<int64_t> px_;         // value offsets (64-bit: the float copy may be large)
  std::vector<int> perm_;
  std::vector<float> x_;
  // Groups of subtrees: group g holds the supernode ranges ranges_[group_start_[g] ..
  // group_start_[g+1]), each [first, last] inclusive, in increasing order. The top: every
  // supernode in no range, in increasing order.
  std::vector<int> group_start_;
  std::vector<std::pair<int, int>> ranges_;
  std::vector<int> top_;
  std::vector<int> top_slot_;  // per column: its index among the top's columns, or -1
  int top_columns_ = 0;
  double top_share_ = 0;
  bool assigned_ = false;
  // Work: the permuted vector, per-group buffers for the top's columns, per-thread scratch.
  std::vector<double> y_, buffers_;
  std::vector<std::vector<double>> scratch_;

  void forward(int s, double* y, double* top_buffer);  // top_buffer null: write y
  void backward(int s, double* y);
};

}  // namespace uvpress::solve
