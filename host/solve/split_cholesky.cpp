// The two-thread split factorization (split_cholesky.h). How:
//
// analyze: cholmod_bisect (METIS's vertex separator, the graph compressed first, so a
// vertex's u and v stay together) gives halves 0 and 1 and the separator S. Each half's own
// block Ai is ordered like a whole system (choose_fill_ordering); Mi is then built in that
// order with S last and analysed in its natural order, not postordered, so that CHOLMOD's
// columns are exactly [half i, S]. A supernode may straddle the boundary: the solves stop
// at the first separator column (the kernels' k, below).
//
// factorize: both halves gather their values from the whole matrix and factorize, one
// thread each; each writes its separator block Ti (dense, s x s). Then S's Schur complement T0 T0' + T1 T1' - C - shift I by two dsyrk calls, and
// dpotrf.
//
// solve: forward through both halves at once (each half's updates of S stay in its own
// vector), S's right-hand side summed in half order, the dense solves with Ls, then
// backward through both halves.
#include "solve/split_cholesky.h"

#include "solve/sparse_system.h"

#include <algorithm>
#include <string>

extern "C" {
void dsyrk_(const char* uplo, const char* trans, const int* n, const int* k, const double* alpha, const double* a,
            const int* lda, const double* beta, double* c, const int* ldc);
void dpotrf_(const char* uplo, const int* n, double* a, const int* lda, int* info);
}

namespace uvpress::solve {

namespace {
// The split pays when the separator is small: its dense factorization and the two
// halves' copies of its block grow as s^3.
constexpr double kMaxSeparatorShare = 0.05;
// ... and the halves even: the slower one is the factorization's time.
constexpr double kMinHalfShare = 0.3;

// The dense work of one supernode in a triangular solve with L (forward) or L'
// (backward), on its rows gathered into w. The supernode is m rows by at least k columns,
// column-major with leading dimension m (CHOLMOD's layout), its first rows its own
// columns; only the first k columns are solved (a half stops at the separator). T is float
// for the preconditioner's copies, double for direct solves; w is double either way.
//
// Forward. In: w[0, k) the right-hand side, w[k, m) zero. Out: w[0, k) solved, w[k, m) the updates
// to add to those rows (minus L(k:m, 0:k) times the solution).
template <class T>
void supernode_forward(const T* L, int m, int k, double* w) {
  for (int j = 0; j < k; ++j) {
    const T* col = L + long(j) * m;
    const double xj = w[j] / double(col[j]);
    w[j] = xj;
    for (int i = j + 1; i < m; ++i) w[i] -= double(col[i]) * xj;
  }
}

// Backward. In: w[0, k) the right-hand side, w[k, m) the solution at those rows. Out:
// w[0, k) solved.
template <class T>
void supernode_backward(const T* L, int m, int k, double* w) {
  for (int j = k - 1; j >= 0; --j) {
    const T* col = L + long(j) * m;
    // Four partial sums in a fixed order: vectorizable, and the same bits everywhere.
    double a0 = 0, a1 = 0, a2 = 0, a3 = 0;
    int i = j + 1;
    for (; i + 4 <= m; i += 4) {
      a0 += double(col[i]) * w[i];
      a1 += double(col[i + 1]) * w[i + 1];
      a2 += double(col[i + 2]) * w[i + 2];
      a3 += double(col[i + 3]) * w[i + 3];
    }
    for (; i < m; ++i) a0 += double(col[i]) * w[i];
    w[j] = (w[j] - ((a0 + a1) + (a2 + a3))) / double(col[j]);
  }
}

}  // namespace

std::string cholmod_failure(int status) {
  return status == CHOLMOD_NOT_POSDEF      ? "factorization failed: matrix not positive definite (CHOLMOD)"
         : status == CHOLMOD_OUT_OF_MEMORY ? "factorization failed: out of memory (CHOLMOD)"
                                           : "factorization failed (CHOLMOD status " + std::to_string(status) + ")";
}

bool SplitCholesky::analyze(const Eigen::SparseMatrix<double>& lower) {
  n_ = int(lower.rows());
  const int* outer = lower.outerIndexPtr();
  const int* inner = lower.innerIndexPtr();
  const long nnz = long(lower.nonZeros());

  std::vector<int> part(size_t(n_), -1);
  {
    cholmod_common& c = half_[0].llt.cholmod();
    cholmod_sparse A{};
    A.nrow = A.ncol = size_t(n_);
    A.nzmax = size_t(nnz);
    A.p = const_cast<int*>(outer);
    A.i = const_cast<int*>(inner);
    A.stype = -1;
    A.itype = CHOLMOD_INT;
    A.xtype = CHOLMOD_PATTERN;
    A.dtype = CHOLMOD_DOUBLE;
    A.sorted = 1;
    A.packed = 1;
    const SerialCholmod serial;
    if (cholmod_bisect(&A, nullptr, 0, 1, part.data(), &c) < 0) return false;
  }
  std::vector<int> count(3, 0);
  for (int p : part) {
    if (p < 0 || p > 2) return false;
    ++count[size_t(p)];
  }
  if (count[2] > kMaxSeparatorShare * n_ || std::min(count[0], count[1]) < kMinHalfShare * n_) return false;
  for (int col = 0; col < n_; ++col)
    for (int k = outer[col]; k < outer[col + 1]; ++k)
      if (part[size_t(inner[k])] + part[size_t(col)] == 1) return false;  // not a separator

  sep_.clear();
  std::vector<int> index(size_t(n_), -1);  // separator index
  for (int g = 0; g < n_; ++g)
    if (part[size_t(g)] == 2) index[size_t(g)] = int(sep_.size()), sep_.push_back(g);
  const int s = int(sep_.size());
  sep_entries_.clear(), sep_entry_row_.clear(), sep_entry_col_.clear();
  for (int col = 0; col < n_; ++col)
    for (int k = outer[col]; k < outer[col + 1]; ++k)
      if (part[size_t(col)] == 2 && part[size_t(inner[k])] == 2) {
        sep_entries_.push_back(uint32_t(k));
        sep_entry_row_.push_back(index[size_t(inner[k])]);
        sep_entry_col_.push_back(index[size_t(col)]);
      }

  flops_ = 2.0 * double(s) * s * s;  // two dsyrk and a dpotrf, about
  entries_ = double(s) * s;
  bool ok[2] = {false, false};
  // One after the other: run on two threads, the halves' orderings (METIS inside
  // CHOLMOD's nested dissection) came out different from run to run (flatten's 1-vs-2
  // threads test failed 1 run in 3), so the analysis stays serial; only the numeric work
  // runs in parallel.
  for (int i = 0; i < 2; ++i) {
    const SerialCholmod serial;
    ok[i] = analyze_half(i, lower, part);
  }
  if (!ok[0] || !ok[1]) return false;
  for (const Half& h : half_) flops_ += h.flops, entries_ += h.entries;
  ls_.assign(size_t(s) * size_t(s), 0.0);
  ls_float_.assign(ls_.size(), 0.0f);
  sep_rhs_.assign(size_t(s), 0.0);
  return true;
}

// Half i of the split: its own block ordered for fill, then M = [A B'; B C] in that order
// with S last, analysed in exactly that order. False when CHOLMOD does not keep it.
// CHOLMOD's loops serial (the caller's SerialCholmod).
bool SplitCholesky::analyze_half(int i, const Eigen::SparseMatrix<double>& lower, const std::vector<int>& part) {
  const int* outer = lower.outerIndexPtr();
  const int* inner = lower.innerIndexPtr();
  const int s = int(sep_.size());
  Half& h = half_[size_t(i)];
  cholmod_common& c = h.llt.cholmod();
  c.print = 0;
  // The half's own block, in ascending global order, ordered for fill.
  std::vector<int> dofs;
  std::vector<int> local(size_t(n_), -1);
  for (int g = 0; g < n_; ++g)
    if (part[size_t(g)] == i) local[size_t(g)] = int(dofs.size()), dofs.push_back(g);
  h.interior = int(dofs.size());
  {
    std::vector<Eigen::Triplet<double>> t;
    for (int col = 0; col < n_; ++col)
      if (part[size_t(col)] == i)
        for (int k = outer[col]; k < outer[col + 1]; ++k)
          if (part[size_t(inner[k])] == i) t.emplace_back(local[size_t(inner[k])], local[size_t(col)], 1.0);
    Eigen::SparseMatrix<double> A(h.interior, h.interior);
    A.setFromTriplets(t.begin(), t.end());
    choose_fill_ordering(c);
    h.llt.analyzePattern(A);
    if (h.llt.info() != Eigen::Success) return false;
    const int* perm = static_cast<const int*>(h.llt.factor().Perm);
    h.dofs.resize(size_t(h.interior));
    for (int j = 0; j < h.interior; ++j) h.dofs[size_t(j)] = dofs[size_t(perm[j])];
  }
  // M = [A B'; B C] in that order, S last: local column of every global dof of the half and S.
  std::fill(local.begin(), local.end(), -1);
  for (int j = 0; j < h.interior; ++j) local[size_t(h.dofs[size_t(j)])] = j;
  for (int q = 0; q < s; ++q) local[size_t(sep_[size_t(q)])] = h.interior + q;
  const int m = h.interior + s;
  struct Entry {
    int col, row;
    uint32_t k;
  };
  std::vector<Entry> entries;
  for (int col = 0; col < n_; ++col) {
    if (local[size_t(col)] < 0) continue;
    for (int k = outer[col]; k < outer[col + 1]; ++k)
      if (const int r = local[size_t(inner[k])]; r >= 0) {
        const int lc = local[size_t(col)];
        entries.push_back({std::min(r, lc), std::max(r, lc), uint32_t(k)});
      }
  }
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return a.col != b.col ? a.col < b.col : a.row < b.row; });
  h.M.resize(m, m);
  h.M.resizeNonZeros(long(entries.size()));
  int* mo = h.M.outerIndexPtr();
  int* mi = h.M.innerIndexPtr();
  std::fill(mo, mo + m + 1, 0);
  h.gather.resize(entries.size());
  for (size_t e = 0; e < entries.size(); ++e) {
    ++mo[entries[e].col + 1];
    mi[e] = entries[e].row;
    h.gather[e] = entries[e].k;
  }
  for (int j = 0; j < m; ++j) mo[j + 1] += mo[j];
  std::fill(h.M.valuePtr(), h.M.valuePtr() + entries.size(), 0.0);
  for (int j = 0; j < m; ++j) h.M.valuePtr()[mo[j]] = 1.0;  // a pattern CHOLMOD can analyse

  c.nmethods = 1;
  c.method[0].ordering = CHOLMOD_NATURAL;
  c.postorder = 0;
  h.llt.analyzePattern(h.M);
  if (h.llt.info() != Eigen::Success) return false;
  const cholmod_factor& L = h.llt.factor();
  const int* perm = static_cast<const int*>(L.Perm);
  for (int j = 0; j < m; ++j)
    if (perm[j] != j) return false;  // CHOLMOD kept its own order: no split
  h.flops = c.fl, h.entries = c.lnz;
  const int* super = static_cast<const int*>(L.super);
  const int* pi = static_cast<const int*>(L.pi);
  h.column_super.assign(size_t(m), 0);
  h.supernodes = 0;
  int rows = 0;
  for (int k = 0; k < int(L.nsuper); ++k) {
    for (int j = super[k]; j < super[k + 1]; ++j) h.column_super[size_t(j)] = k;
    if (super[k] < h.interior) h.supernodes = k + 1;
    rows = std::max(rows, pi[k + 1] - pi[k]);
  }
  h.y.assign(size_t(m), 0.0);
  h.w.assign(size_t(rows), 0.0);
  h.separator.assign(size_t(s) * size_t(s), 0.0);
  return true;
}

bool SplitCholesky::factorize(const Eigen::SparseMatrix<double>& lower, double shift) {
  failure_.clear();
  const double* v = lower.valuePtr();
  const int s = int(sep_.size());
  int status[2] = {CHOLMOD_OK, CHOLMOD_OK};
  {
#pragma omp parallel for schedule(static, 1)
    for (int i = 0; i < 2; ++i) {
      const SerialCholmod serial;  // this thread's CHOLMOD loops (an ICV of its own task)
      Half& h = half_[size_t(i)];
      double* mv = h.M.valuePtr();
      for (size_t k = 0; k < h.gather.size(); ++k) mv[k] = v[h.gather[k]];
      h.llt.setShift(shift);
      h.llt.factorize(h.M);
      if (h.llt.info() != Eigen::Success) {
        status[i] = h.llt.cholmod().status == CHOLMOD_OK ? CHOLMOD_NOT_POSDEF : h.llt.cholmod().status;
        continue;
      }
      const cholmod_factor& L = h.llt.factor();
      const int* super = static_cast<const int*>(L.super);
      const int* pi = static_cast<const int*>(L.pi);
      const int* px = static_cast<const int*>(L.px);
      const int* rows = static_cast<const int*>(L.s);
      const double* x = static_cast<const double*>(L.x);
      // Ti: the factor's separator block, dense.
      for (int q = 0; q < s; ++q) {
        const int j = h.interior + q, k = h.column_super[size_t(j)];
        const int m = pi[k + 1] - pi[k], offset = j - super[k];
        const double* col = x + px[k] + long(offset) * m;
        for (int r = offset; r < m; ++r) h.separator[size_t(rows[pi[k] + r] - h.interior) + size_t(q) * size_t(s)] = col[r];
      }
    }
  }
  floats_current_ = false;
  for (int i = 0; i < 2; ++i)
    if (status[i] != CHOLMOD_OK) {
      failure_ = cholmod_failure(status[i]);
      return false;
    }
  // Schur complement of S: T0 T0' + T1 T1' - C - shift I, lower triangle (dsyrk and
  // dpotrf leave the upper one zero, as the solves' kernels want it).
  std::fill(ls_.begin(), ls_.end(), 0.0);
  const double one = 1, zero = 0;
  dsyrk_("L", "N", &s, &s, &one, half_[0].separator.data(), &s, &zero, ls_.data(), &s);
  dsyrk_("L", "N", &s, &s, &one, half_[1].separator.data(), &s, &one, ls_.data(), &s);
  for (size_t e = 0; e < sep_entries_.size(); ++e)
    ls_[size_t(sep_entry_row_[e]) + size_t(sep_entry_col_[e]) * size_t(s)] -= v[sep_entries_[e]];
  for (int q = 0; q < s; ++q) ls_[size_t(q) * size_t(s + 1)] -= shift;
  int info = 0;
  dpotrf_("L", &s, ls_.data(), &s, &info);
  if (info != 0) {
    failure_ = "factorization failed: matrix not positive definite (LAPACK, at the separator)";
    return false;
  }
  return true;
}

// One triangular sweep through a half's columns: with L (forward, supernodes in order,
// the separator's rows collecting updates in h.y) or with L' (backward, in reverse order,
// the separator's solution read from h.y).
template <class T>
void SplitCholesky::sweep(Half& h, const T* factor, bool forward) {
  const cholmod_factor& L = h.llt.factor();
  const int* super = static_cast<const int*>(L.super);
  const int* pi = static_cast<const int*>(L.pi);
  const int* px = static_cast<const int*>(L.px);
  double* y = h.y.data();
  double* w = h.w.data();
  for (int step = 0; step < h.supernodes; ++step) {
    const int k = forward ? step : h.supernodes - 1 - step;
    const int c0 = super[k], m = pi[k + 1] - pi[k];
    const int cols = std::min(super[k + 1], h.interior) - c0;
    const int* rows = static_cast<const int*>(L.s) + pi[k];
    if (forward) {
      for (int i = 0; i < cols; ++i) w[i] = y[c0 + i];
      for (int i = cols; i < m; ++i) w[i] = 0;
      supernode_forward(factor + px[k], m, cols, w);
      for (int i = cols; i < m; ++i) y[rows[i]] += w[i];
    } else {
      for (int i = 0; i < m; ++i) w[i] = y[rows[i]];
      supernode_backward(factor + px[k], m, cols, w);
    }
    for (int i = 0; i < cols; ++i) y[c0 + i] = w[i];
  }
}

template <class T>
void SplitCholesky::apply(const double* b, double* x, const T* factor0, const T* factor1, const T* ls) {
  const int s = int(sep_.size());
  const T* factor[2] = {factor0, factor1};
#pragma omp parallel for schedule(static, 1)
  for (int i = 0; i < 2; ++i) {
    Half& h = half_[size_t(i)];
    for (int j = 0; j < h.interior; ++j) h.y[size_t(j)] = b[h.dofs[size_t(j)]];
    std::fill(h.y.begin() + h.interior, h.y.end(), 0.0);
    sweep(h, factor[i], true);
  }
  for (int q = 0; q < s; ++q)
    sep_rhs_[size_t(q)] = b[sep_[size_t(q)]] + half_[0].y[size_t(half_[0].interior + q)] +
                          half_[1].y[size_t(half_[1].interior + q)];
  supernode_forward(ls, s, s, sep_rhs_.data());
  supernode_backward(ls, s, s, sep_rhs_.data());
#pragma omp parallel for schedule(static, 1)
  for (int i = 0; i < 2; ++i) {
    Half& h = half_[size_t(i)];
    std::copy(sep_rhs_.begin(), sep_rhs_.end(), h.y.begin() + h.interior);
    sweep(h, factor[i], false);
    for (int j = 0; j < h.interior; ++j) x[h.dofs[size_t(j)]] = h.y[size_t(j)];
  }
  for (int q = 0; q < s; ++q) x[sep_[size_t(q)]] = sep_rhs_[size_t(q)];
}

std::vector<int> SplitCholesky::elimination_order() const {
  std::vector<int> order = half_[0].dofs;
  order.insert(order.end(), half_[1].dofs.begin(), half_[1].dofs.end());
  order.insert(order.end(), sep_.begin(), sep_.end());
  return order;
}

void SplitCholesky::solve(const double* b, double* x) {
  apply(b, x, static_cast<const double*>(half_[0].llt.factor().x), static_cast<const double*>(half_[1].llt.factor().x),
        ls_.data());
}

void SplitCholesky::precondition(const double* r, double* z) {
  if (!floats_current_) {  // the first preconditioning since the factorization: copy it once
#pragma omp parallel for schedule(static, 1)
    for (int i = 0; i < 2; ++i) {
      Half& h = half_[size_t(i)];
      const cholmod_factor& L = h.llt.factor();
      const double* x = static_cast<const double*>(L.x);
      const long size = h.supernodes ? long(static_cast<const int*>(L.px)[h.supernodes]) : 0;
      h.x_float.resize(size_t(size));
      for (long e = 0; e < size; ++e) h.x_float[size_t(e)] = float(x[e]);
    }
    for (size_t e = 0; e < ls_.size(); ++e) ls_float_[e] = float(ls_[e]);
    floats_current_ = true;
  }
  apply(r, z, half_[0].x_float.data(), half_[1].x_float.data(), ls_float_.data());
}

}  // namespace uvpress::solve
