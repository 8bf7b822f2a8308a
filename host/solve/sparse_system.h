// The 2V x 2V linear system of one Newton-type step, H d = -grad E (flatten's SLIM and CM
// steps, the mesh stage's damped Newton step), u and v coupled (dof 2i = u_i, 2i+1 = v_i).
// The sparsity pattern depends on the connectivity only, so it is built, and CHOLMOD's
// symbolic analysis (ordering, supernodes) done, once per mesh; every iteration then
// assembles values into the fixed pattern and refactorizes numerically (supernodal LLT on
// OpenBLAS; from kSplitMinDofs on, split in two halves factorized at once, split_cholesky.h)
// or runs PCG on an earlier factor (solve_reusing). Vertex 0 is pinned (the
// translation null space), which leaves the step unchanged. The result is bit-identical
// whatever the OpenMP thread count (BLAS threads: configure_blas_threads, below). How
// assembly, factorization reuse and the pinning work, with measurements: the top of
// sparse_system.cpp.
#pragma once

#include "solve/pcg.h"
#include "solve/split_cholesky.h"

#include <Eigen/CholmodSupport>
#include <Eigen/Sparse>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace uvpress::solve {

class SparseSystem {
 public:
  SparseSystem(size_t vertex_count, const std::vector<uint32_t>& triangles);

  // hess21[21 t + k]: lower triangle of triangle t's 6x6 Hessian (local dofs u0 v0 u1 v1
  // u2 v2), row-major: (0,0) (1,0) (1,1) (2,0) ... (5,5) (triangle_energy.h's hess21_index).
  void assemble(const std::vector<double>& hess21);
  // grad6[6 t + k] -> grad (2V), fixed order.
  void gather_gradient(const std::vector<double>& grad6, std::vector<double>& grad) const;
  // Numeric factorization of the assembled matrix. Returns false when it fails: an entry
  // that is not finite (CHOLMOD is not called: what it does with NaN depends on the BLAS),
  // or CHOLMOD finds the matrix not positive definite or runs out of memory. failure() then
  // says which, in words ("" after a success).
  bool factorize();
  const std::string& failure() const { return failure_; }
  // Test hook: the n-th call of factorize() (1-based; 0, the default, never) negates the
  // assembled matrix first, so that CHOLMOD itself meets a matrix that is not positive
  // definite - a deterministic stand-in for the numerical breakdowns real inputs cause.
  void break_factorization(int n) { break_at_ = n; }
  // Solves H d = -grad with vertex 0 pinned, by the last factorization.
  void solve(const std::vector<double>& grad, std::vector<double>& d);
  // Solves H d = -grad for the assembled H, vertex 0 pinned: PCG on the last factorization
  // (started from d = 0, so every iterate is a descent direction of the quadratic model)
  // until the preconditioned residual norm falls by `tolerance`; when the budget runs out,
  // or there is no factor yet, factorizes H and solves directly. Returns false when that
  // factorization fails (failure() says why).
  struct SolveStats {
    bool factorized = false;  // H was factorized (after PCG ran out of budget, or with no factor yet)
    int pcg_iterations = 0;   // spent in this call, whether or not PCG converged
    double t_factorization = 0, t_solve = 0;  // seconds; t_solve includes PCG
  };
  bool solve_reusing(const std::vector<double>& grad, std::vector<double>& d, double tolerance, SolveStats& stats);

  size_t nonzeros() const { return size_t(matrix_.nonZeros()); }
  // The vertices in the order of the analysis's fill-reducing ordering (each where its
  // first dof is eliminated): a good elimination order for other systems on the same mesh
  // (flatten's Tutte embedding), without ordering again.
  std::vector<uint32_t> vertex_order() const;
  int factorizations() const { return factorizations_; }
  long pcg_iterations() const { return pcg_iterations_; }
  int pcg_budget() const { return pcg_budget_; }
  // Overrides the budget fixed at analysis (tests: force the PCG path on small meshes).
  void set_pcg_budget(int iterations) { pcg_budget_ = iterations; }

 private:
  size_t n_;  // dofs
  Eigen::SparseMatrix<double> matrix_;  // lower triangle, column-major
  std::vector<uint32_t> gather_start_, gather_;         // per nonzero: hess21 indices
  std::vector<uint32_t> vertex_start_, vertex_corner_;  // per vertex: 3 t + corner
  std::vector<uint32_t> pinned_entries_;  // nonzeros in the rows/columns of dofs 0 and 1
  SupernodalLLT solver_;
  SplitCholesky split_;  // used instead of solver_ on large systems (split_active_)
  bool split_active_ = false;
  double diagonal_mean_ = 1;
  std::string failure_;
  int factorizations_ = 0, break_at_ = 0;
  int pcg_budget_ = 0;
  long pcg_iterations_ = 0;
  bool factored_ = false;  // solver_ holds the factor of some earlier H
  bool skip_attempt_ = false;  // the last PCG attempt failed
  std::vector<double> rhs_;  // -grad, pinned
  PcgWork work_;

  double shift() const { return 1e-10 * diagonal_mean_; }
  // y = (H + shift) x for the lower triangle stored in matrix_: sequential, fixed order.
  void multiply(const std::vector<double>& x, std::vector<double>& y) const;
  // z = the last factor's inverse applied to r (split: its float copy).
  void precondition(const std::vector<double>& r, std::vector<double>& z);
  // PCG from d = 0; true when it converged within the budget.
  bool pcg(const std::vector<double>& grad, std::vector<double>& d, double tolerance);
};

// Determinism: OpenBLAS splits the supernodal kernels differently for different thread
// counts, and the factor's bits change with them. uvpress therefore runs BLAS on one
// thread (openblas_set_num_threads(1), looked up at run time) unless UVPRESS_BLAS_THREADS=N
// asks for more - faster factorizations on big machines, bit-identical only for equal N.
// The per-triangle OpenMP loops are bit-identical for any OMP_NUM_THREADS.
void configure_blas_threads();

// Fill-reducing ordering for a mesh's system: CHOLMOD tries AMD and its nested dissection
// (NESDIS) and keeps the one with less fill. Measured on camelhead subdivided 0-2 times
// (22.7K-363K faces), nested dissection needs 40 %, 60 % and 64 % fewer flops than AMD;
// CHOLMOD's default (AMD, METIS only when AMD's fill looks bad) took AMD on the first two.
// AMD stays for small meshes, where it wins and nested dissection's analysis costs more
// than it saves.
void choose_fill_ordering(cholmod_common& c);

// CHOLMOD (Debian's build) runs parts of its supernodal factorization - the scatter of
// each update into its ancestor supernode - as OpenMP loops with a fixed 4 threads,
// whatever the machine. On 2 cores that oversubscribes, and most supernodes of a mesh
// are small, so the threads mostly wake and wait: measured on camelhead subdivided once
// and twice, a factorization takes 1.6x as long as with those loops serial. The loops only
// scatter (each entry written by one thread), so serial gives the same bits. While an
// object of this type lives, parallel regions opened on this thread run with one thread;
// uvpress's own OpenMP loops never run inside CHOLMOD calls.
// The limit is an ICV of the calling thread's task (libgomp), so each of split_cholesky's
// two threads sets its own.
class SerialCholmod {
 public:
  SerialCholmod();
  ~SerialCholmod();
  SerialCholmod(const SerialCholmod&) = delete;
  SerialCholmod& operator=(const SerialCholmod&) = delete;

 private:
  int levels_;
};

}  // namespace uvpress::solve
