// The sparse system of a Newton-type step (sparse_system.h). How:
//
// Assembly is a gather, not a scatter: for every stored nonzero, the list of per-triangle
// Hessian entries that add into it, in triangle order. Parallel over nonzeros, and the
// sums come out bit-identical whatever the thread count. Same for the gradient, per vertex.
//
// Factorization reuse: H changes slowly from one iteration to the next, and at 10^4-10^6
// faces its numeric factorization is nearly the whole cost of a step (camelhead-s2: 87 %).
// solve_reusing() therefore solves with preconditioned conjugate gradients, the
// preconditioner being the factor of an earlier H, and refactorizes only when PCG does not
// reach its tolerance within a budget of iterations that costs a fraction of one
// factorization. A PCG iteration is a pair of triangular solves, memory-bound: a
// factorization costs only 10-13 of them, so the gain is bounded (docs/DEVELOPERS.md,
// "flatten at scale"). The budget is fixed from CHOLMOD's flop and fill counts at analysis time, not
// from timings, so the sequence of factorizations and PCG iterations - and every bit of
// the result - is the same on every machine and for every thread count. Small meshes get
// a budget of 0: a factorization there costs a few solves, and the direct path is kept bit
// for bit.
//
// Translation null space: E is invariant under translating all UVs, so H has the two
// translations in its kernel (and grad E is orthogonal to them). Vertex 0 is pinned: its
// two rows and columns are replaced by the identity (scaled to the mean diagonal) and its
// right-hand side by 0. The solution of the pinned system is the minimum of the quadratic
// model among steps that leave vertex 0 in place - exactly the unpinned solution up to a
// translation, so the step is unchanged. A diagonal shift of 1e-10 x the mean diagonal on
// top guards against other (numerically) singular modes of the CM proxy, where dropping
// the alpha term can leave a triangle's rotation direction without curvature.
#include "solve/sparse_system.h"

#include "core/parallel.h"
#include "core/stopwatch.h"
#include "solve/triangle_energy.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <cstdlib>
#include <dlfcn.h>
#include <mutex>
#include <omp.h>

namespace uvpress::solve {

namespace {
// Systems from this many dofs on are factorized split in two (split_cholesky.h). Measured
// on camelhead (22.7K dofs): 0.050 -> 0.042 s a factorization, and, the budget below
// counting the separator's dense work, 11 factorizations instead of 15 (t_c 1.0 -> 0.7 s,
// E_c within 2e-9); on camelhead-s1 and -s2 a factorization is 2x faster.
constexpr size_t kSplitMinDofs = 20000;

// PCG iterations one solve may spend on an old factor before refactorizing. A PCG iteration
// is two triangular solves (4 lnz flops) and a product with H (4 nnz flops); a numeric
// factorization is `fl` flops. The solves are memory-bound BLAS-2 and run about
// kSolveSlowdown times fewer flops per second than the BLAS-3 factorization (measured on
// camelhead subdivided 0-2 times, OpenBLAS on one thread: a factorization costs 10-13 PCG
// iterations there). A failed attempt may waste at most kBudgetShare of a factorization.
// Since the split and its float preconditioner (split_cholesky.h) a factorization costs
// about 25 PCG iterations on camelhead-s2; budgets of 15 and 30 saved no factorization
// there (the stale factors fail in the first steps either way), so the budget stays.
int reuse_budget(double fl, double lnz, double nnz) {
  constexpr double kSolveSlowdown = 5, kBudgetShare = 0.5;
  return int(std::min(100.0, kBudgetShare * fl / (kSolveSlowdown * (4 * lnz + 4 * nnz))));
}

}  // namespace

void configure_blas_threads() {
  static std::once_flag once;
  std::call_once(once, [] {
    int n = 1;
    if (const char* env = std::getenv("UVPRESS_BLAS_THREADS"); env && std::atoi(env) > 0) n = std::atoi(env);
    // Found at run time: CHOLMOD reaches BLAS and LAPACK through libblas.so.3 and
    // liblapack.so.3 (Debian alternatives), and OpenBLAS may also be loaded as
    // libopenblas.so.0 - separate copies with separate thread settings. Set every one.
    using SetThreads = void (*)(int);
    for (const char* lib : {"libblas.so.3", "liblapack.so.3", "libopenblas.so.0"})
      if (void* h = dlopen(lib, RTLD_NOW | RTLD_NOLOAD)) {
        if (auto set = reinterpret_cast<SetThreads>(dlsym(h, "openblas_set_num_threads"))) set(n);
        dlclose(h);
      }
    if (auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"))) set(n);
  });
}

SerialCholmod::SerialCholmod() : levels_(omp_get_max_active_levels()) { omp_set_max_active_levels(0); }
SerialCholmod::~SerialCholmod() { omp_set_max_active_levels(levels_); }

SparseSystem::SparseSystem(size_t nv, const std::vector<uint32_t>& tris) : n_(2 * nv) {
  configure_blas_threads();
  const size_t nt = tris.size() / 3;
  // Pattern: every (vertex, vertex) pair of every triangle, 2x2 blocks, lower triangle, and
  // the whole diagonal. Built per vertex column - the vertex itself, then the vertices after
  // it that share a triangle with it, sorted - and expanded to dofs, rather than by sorting
  // 21 triplets a triangle (camelhead-s2: 1.2 s of the set-up).
  std::vector<uint32_t> adj_start(nv + 1, 0), adj;
  {
    std::vector<uint32_t> start(nv + 1, 0);
    for (size_t v = 0; v < nv; ++v) start[v + 1] = 1;
    for (size_t t = 0; t < nt; ++t)
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
          if (tris[3 * t + size_t(a)] > tris[3 * t + size_t(b)]) ++start[tris[3 * t + size_t(b)] + 1];
    for (size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
    std::vector<uint32_t> all(start[nv]), fill(start.begin(), start.end() - 1);
    for (size_t v = 0; v < nv; ++v) all[fill[v]++] = uint32_t(v);
    for (size_t t = 0; t < nt; ++t)
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
          if (tris[3 * t + size_t(a)] > tris[3 * t + size_t(b)])
            all[fill[tris[3 * t + size_t(b)]]++] = tris[3 * t + size_t(a)];
    adj.reserve(all.size());
    for (size_t v = 0; v < nv; ++v) {
      std::sort(all.begin() + start[v] + 1, all.begin() + start[v + 1]);
      adj.push_back(uint32_t(v));
      for (uint32_t i = start[v] + 1; i < start[v + 1]; ++i)
        if (all[i] != adj.back()) adj.push_back(all[i]);
      adj_start[v + 1] = uint32_t(adj.size());
    }
  }
  // Dofs: column 2c holds rows 2c, 2c+1, then 2r, 2r+1 for each later neighbour r; column
  // 2c+1 the same without row 2c.
  matrix_.resize(long(n_), long(n_));
  matrix_.resizeNonZeros(long(4 * (adj.size() - nv) + 3 * nv));
  {
    int* outer = matrix_.outerIndexPtr();
    int* inner = matrix_.innerIndexPtr();
    int k = 0;
    for (size_t c = 0; c < nv; ++c)
      for (int q = 0; q < 2; ++q) {
        outer[2 * c + size_t(q)] = k;
        if (q == 0) inner[k++] = int(2 * c);
        inner[k++] = int(2 * c + 1);
        for (uint32_t i = adj_start[c] + 1; i < adj_start[c + 1]; ++i) inner[k++] = int(2 * adj[i]), inner[k++] = int(2 * adj[i] + 1);
      }
    outer[n_] = k;
    std::fill(matrix_.valuePtr(), matrix_.valuePtr() + k, 1.0);
  }

  // Gather lists: for each nonzero, which hess21 entries add into it (triangle order).
  const auto* outer = matrix_.outerIndexPtr();
  const auto* inner = matrix_.innerIndexPtr();
  auto position = [&](long row, long col) {  // row >= col: the entry's index, from the vertex lists
    const uint32_t rv = uint32_t(row / 2), cv = uint32_t(col / 2);
    const int p = int(row % 2), q = int(col % 2);
    const uint32_t* first = adj.data() + adj_start[cv];
    const uint32_t* last = adj.data() + adj_start[cv + 1];
    const uint32_t k = rv == cv ? 0 : uint32_t(std::lower_bound(first + 1, last, rv) - first);
    return uint32_t(outer[col]) + (k == 0 ? uint32_t(p - q) : 2 * k + uint32_t(p) - uint32_t(q));
  };
  const size_t nnz = size_t(matrix_.nonZeros());
  std::vector<uint32_t> target(nt * 21);
  gather_start_.assign(nnz + 1, 0);
  for (size_t t = 0; t < nt; ++t)
    for (int a = 0; a < 6; ++a)
      for (int b = 0; b <= a; ++b) {
        const long ga = 2 * long(tris[3 * t + size_t(a / 2)]) + a % 2, gb = 2 * long(tris[3 * t + size_t(b / 2)]) + b % 2;
        const uint32_t k = position(std::max(ga, gb), std::min(ga, gb));
        target[21 * t + size_t(hess21_index(a, b))] = k;
        ++gather_start_[k + 1];
      }
  for (size_t k = 0; k < nnz; ++k) gather_start_[k + 1] += gather_start_[k];
  gather_.resize(nt * 21);
  {
    std::vector<uint32_t> fill(gather_start_.begin(), gather_start_.end() - 1);
    for (size_t e = 0; e < nt * 21; ++e) gather_[fill[target[e]]++] = uint32_t(e);
  }
  // Entries in the rows or columns of the pinned dofs 0 and 1.
  for (long col = 0; col < long(n_); ++col)
    for (long k = outer[col]; k < outer[col + 1]; ++k)
      if (col <= 1 || inner[k] <= 1) pinned_entries_.push_back(uint32_t(k));

  vertex_start_.assign(nv + 1, 0);
  for (uint32_t v : tris) ++vertex_start_[v + 1];
  for (size_t v = 0; v < nv; ++v) vertex_start_[v + 1] += vertex_start_[v];
  vertex_corner_.resize(tris.size());
  {
    std::vector<uint32_t> fill(vertex_start_.begin(), vertex_start_.end() - 1);
    for (size_t c = 0; c < tris.size(); ++c) vertex_corner_[fill[tris[c]]++] = uint32_t(c);
  }

  if (n_ >= kSplitMinDofs && split_.analyze(matrix_)) {
    split_active_ = true;
    pcg_budget_ = reuse_budget(split_.flops(), split_.entries(), double(matrix_.nonZeros()));
    return;
  }
  cholmod_common& c = solver_.cholmod();
  choose_fill_ordering(c);
  {
    const SerialCholmod serial;
    solver_.analyzePattern(matrix_);
  }
  pcg_budget_ = reuse_budget(c.fl, c.lnz, double(matrix_.nonZeros()));
}

void choose_fill_ordering(cholmod_common& c) {
  c.print = 0;  // no warnings on stdout: a failure is reported by failure()
  c.nmethods = 2;
  c.method[0].ordering = CHOLMOD_AMD;
  c.method[1].ordering = CHOLMOD_NESDIS;
  c.postorder = 1;
}

std::vector<uint32_t> SparseSystem::vertex_order() const {
  std::vector<int> dofs;
  if (split_active_) {
    dofs = split_.elimination_order();
  } else {
    const int* perm = static_cast<const int*>(solver_.factor().Perm);
    dofs.assign(perm, perm + n_);
  }
  std::vector<uint32_t> order;
  std::vector<uint8_t> seen(n_ / 2, 0);
  for (int d : dofs)
    if (!seen[size_t(d / 2)]) seen[size_t(d / 2)] = 1, order.push_back(uint32_t(d / 2));
  return order;
}

void SparseSystem::assemble(const std::vector<double>& hess21) {
  double* values = matrix_.valuePtr();
  const long nnz = long(matrix_.nonZeros());
#pragma omp parallel for schedule(static) if (worth_threads(nnz))
  for (long k = 0; k < nnz; ++k) {
    double s = 0;
    for (uint32_t e = gather_start_[size_t(k)]; e < gather_start_[size_t(k) + 1]; ++e) s += hess21[gather_[e]];
    values[k] = s;
  }
  // Mean diagonal (fixed order), then pin dofs 0 and 1.
  const auto* outer = matrix_.outerIndexPtr();
  double sum = 0;
  for (size_t col = 0; col < n_; ++col) sum += values[outer[col]];  // first entry of a column is its diagonal
  diagonal_mean_ = sum > 0 ? sum / double(n_) : 1.0;
  for (uint32_t k : pinned_entries_) values[k] = 0;
  values[outer[0]] = diagonal_mean_;
  values[outer[1]] = diagonal_mean_;
}

void SparseSystem::gather_gradient(const std::vector<double>& grad6, std::vector<double>& grad) const {
  const long nv = long(vertex_start_.size() - 1);
  grad.assign(2 * size_t(nv), 0.0);
#pragma omp parallel for schedule(static) if (worth_threads(nv))
  for (long v = 0; v < nv; ++v) {
    double gu = 0, gv = 0;
    for (uint32_t i = vertex_start_[size_t(v)]; i < vertex_start_[size_t(v) + 1]; ++i) {
      const uint32_t c = vertex_corner_[i];
      const size_t t = c / 3, corner = c % 3;
      gu += grad6[6 * t + 2 * corner], gv += grad6[6 * t + 2 * corner + 1];
    }
    grad[2 * size_t(v)] = gu, grad[2 * size_t(v) + 1] = gv;
  }
}

bool SparseSystem::factorize() {
  failure_.clear();
  double* values = matrix_.valuePtr();
  const long nnz = long(matrix_.nonZeros());
  if (++factorizations_ == break_at_)
    for (long k = 0; k < nnz; ++k) values[k] = -values[k];
  long bad = 0;
  for (long k = 0; k < nnz; ++k) bad += !std::isfinite(values[k]);
  if (bad) {
    factored_ = false;
    failure_ = "factorization failed: " + std::to_string(bad) + " non-finite matrix entries";
    return false;
  }
  if (split_active_) {
    factored_ = split_.factorize(matrix_, shift());
    failure_ = split_.failure();
    return factored_;
  }
  solver_.setShift(shift());
  {
    const SerialCholmod serial;
    solver_.factorize(matrix_);
  }
  factored_ = solver_.info() == Eigen::Success;
  if (factored_) return true;
  failure_ = cholmod_failure(solver_.cholmod().status);
  return false;
}

void SparseSystem::solve(const std::vector<double>& grad, std::vector<double>& d) {
  Eigen::VectorXd rhs(static_cast<Eigen::Index>(n_));
  for (size_t i = 0; i < n_; ++i) rhs[long(i)] = -grad[i];
  rhs[0] = rhs[1] = 0;
  if (split_active_) {
    d.resize(n_);
    split_.solve(rhs.data(), d.data());
    return;
  }
  const SerialCholmod serial;
  Eigen::VectorXd x = solver_.solve(rhs);
  d.assign(x.data(), x.data() + n_);
}

bool SparseSystem::solve_reusing(const std::vector<double>& grad, std::vector<double>& d, double tolerance,
                                 SolveStats& stats) {
  Stopwatch clock;
  failure_.clear();
  stats = {};
  const long before = pcg_iterations_;
  // After a failed attempt the next solve factorizes without trying: while H moves fast
  // (the first SLIM and CM steps) a one-step-old factor fails as well, and every other
  // attempt is enough to notice when it has settled.
  const bool attempt = factored_ && pcg_budget_ > 0 && !skip_attempt_;
  const bool reused = attempt && pcg(grad, d, tolerance);
  skip_attempt_ = attempt && !reused;
  stats.pcg_iterations = int(pcg_iterations_ - before);
  if (reused) {
    stats.t_solve = clock.lap();
    return true;
  }
  stats.t_solve = clock.lap();  // a PCG attempt that ran out of budget
  stats.factorized = true;
  const bool ok = factorize();
  stats.t_factorization = clock.lap();
  if (!ok) return false;
  solve(grad, d);
  stats.t_solve += clock.lap();
  return true;
}

void SparseSystem::multiply(const std::vector<double>& x, std::vector<double>& y) const {
  const auto* outer = matrix_.outerIndexPtr();
  const auto* inner = matrix_.innerIndexPtr();
  const double* values = matrix_.valuePtr();
  const double sigma = shift();
  y.assign(n_, 0.0);
  for (size_t col = 0; col < n_; ++col) {
    // The first stored entry of a column is its diagonal; the rest lie below it.
    double sum = (values[outer[col]] + sigma) * x[col];
    const double xc = x[col];
    for (long k = outer[col] + 1; k < outer[col + 1]; ++k) {
      const size_t row = size_t(inner[k]);
      sum += values[k] * x[row];
      y[row] += values[k] * xc;
    }
    y[col] += sum;
  }
}

void SparseSystem::precondition(const std::vector<double>& r, std::vector<double>& z) {
  if (split_active_) {
    z.resize(n_);
    split_.precondition(r.data(), z.data());
    return;
  }
  const Eigen::Map<const Eigen::VectorXd> rhs(r.data(), long(n_));
  const SerialCholmod serial;
  const Eigen::VectorXd x = solver_.solve(rhs);
  z.assign(x.data(), x.data() + n_);
}

bool SparseSystem::pcg(const std::vector<double>& grad, std::vector<double>& d, double tolerance) {
  rhs_.resize(n_);
  for (size_t i = 0; i < n_; ++i) rhs_[i] = -grad[i];
  rhs_[0] = rhs_[1] = 0;
  const PcgResult res = solve::pcg([this](const std::vector<double>& x, std::vector<double>& y) { multiply(x, y); },
                                   [this](const std::vector<double>& r, std::vector<double>& z) { precondition(r, z); },
                                   rhs_, d, tolerance, pcg_budget_, work_);
  pcg_iterations_ += res.iterations;
  return res.stop == PcgStop::Converged;
}

}  // namespace uvpress::solve
