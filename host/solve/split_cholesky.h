// The top level of nested dissection on two threads: a sparse Cholesky factorization of an
// SPD matrix split at a vertex separator S into two halves that CHOLMOD factorizes at the
// same time, each on one thread, with one small dense factorization where they meet.
//
// Why: CHOLMOD's supernodal factorization runs on one thread here (its BLAS on one thread,
// so that the factor's bits do not depend on the thread count, sparse_system.h), and
// OpenBLAS threads gain little on a mesh's small supernodes (13 % on camelhead-s3). The two
// halves of a nested dissection are independent until the separator: with the dofs ordered
// [half 0, half 1, S],
//
//   H = [A0 0 B0'; 0 A1 B1'; B0 B1 C],   L = [L0 0 0; 0 L1 0; W0 W1 Ls],
//   Li = chol(Ai), Wi = Bi Li^-T, Ls = chol(C - W0 W0' - W1 W1').
//
// CHOLMOD factorizes Mi = [Ai Bi'; Bi C], S ordered last: its factor holds Li and Wi, and
// in its last block chol(C - Wi Wi'), =: Ti. So C - W0 W0' - W1 W1' = T0 T0' + T1 T1' - C,
// the separator's Schur complement, which LAPACK factorizes (dpotrf) into Ls.
//
// Determinism: the split, the halves' orderings and every operation's order depend on the
// matrix's pattern only, and each half is one sequential CHOLMOD call on one thread; with
// one thread the halves run one after the other and give the same bits.
#pragma once

#include <Eigen/CholmodSupport>
#include <Eigen/Sparse>

#include <cstdint>
#include <string>
#include <vector>

namespace uvpress::solve {

// Eigen's CHOLMOD supernodal LL' of a lower-stored matrix, its factor readable.
struct SupernodalLLT : Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> {
  const cholmod_factor& factor() const { return *m_cholmodFactor; }
};

// A failed CHOLMOD factorization's reason in words, from cholmod_common::status.
std::string cholmod_failure(int status);

class SplitCholesky {
 public:
  // Finds the separator (METIS through cholmod_bisect) and analyses both halves. `lower`:
  // the matrix's lower triangle, column-major, diagonal first in every column (pattern
  // only). Returns false, and the caller factorizes whole, when the split would not pay:
  // a separator larger than kMaxSeparatorShare of the dofs or halves too uneven.
  bool analyze(const Eigen::SparseMatrix<double>& lower);
  // Numeric factorization of lower + shift I (lower's values, same pattern as analyzed).
  // False when it fails; failure() says why.
  bool factorize(const Eigen::SparseMatrix<double>& lower, double shift);
  const std::string& failure() const { return failure_; }
  // x = H^-1 b with the double factors.
  void solve(const double* b, double* x);
  // z = H~^-1 r with float copies of the factors: PCG's preconditioner, where a solve is the
  // whole cost of an iteration and, with one right-hand side, bound by memory bandwidth;
  // half the bytes make it about twice as fast. Both sweeps use the same float factor, so
  // the preconditioner is exactly H~ = L~ L~', symmetric positive definite, within 2^-24
  // of the double factor entry by entry; PCG's theory holds for it unchanged.
  void precondition(const double* r, double* z);

  // Analysis figures: CHOLMOD's flop and entry counts of both halves plus the separator's
  // dense work, and the separator's size.
  double flops() const { return flops_; }
  double entries() const { return entries_; }
  int separator() const { return int(sep_.size()); }
  // The dofs in elimination order: half 0's, half 1's, then the separator's.
  std::vector<int> elimination_order() const;

 private:
  struct Half {
    std::vector<int> dofs;            // global dof of each local column < interior
    int interior = 0;                 // local columns [0, interior) are the half, then S
    Eigen::SparseMatrix<double> M;    // local lower triangle, in factorization order
    std::vector<uint32_t> gather;     // per local nonzero: the global nonzero it copies
    SupernodalLLT llt;
    std::vector<int> column_super;    // per local column: its supernode
    int supernodes = 0;               // supernodes with a column < interior
    std::vector<double> separator;    // Ti: the factor's S block, s x s column-major
    std::vector<float> x_float;       // the factor's values, float (made by precondition())
    std::vector<double> y, w;         // work: local vector, one supernode's rows
    double flops = 0, entries = 0;    // CHOLMOD's analysis of M
  };
  Half half_[2];
  int n_ = 0;
  std::vector<int> sep_;                 // global dof of each separator index
  std::vector<uint32_t> sep_entries_;    // global nonzeros with row and column in S
  std::vector<int> sep_entry_row_, sep_entry_col_;  // their separator indices
  std::vector<double> ls_;               // Ls, s x s column-major (upper part zero)
  std::vector<float> ls_float_;
  bool floats_current_ = false;          // the float copies are of the last factorization
  std::vector<double> sep_rhs_, sep_w_;
  double flops_ = 0, entries_ = 0;
  std::string failure_;

  bool analyze_half(int i, const Eigen::SparseMatrix<double>& lower, const std::vector<int>& part);
  template <class T>
  void apply(const double* b, double* x, const T* factor0, const T* factor1, const T* ls);
  template <class T>
  void sweep(Half& h, const T* factor, bool forward);
};

}  // namespace uvpress::solve
