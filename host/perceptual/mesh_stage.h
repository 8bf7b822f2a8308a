// The mesh-wise stage of the perceptual-loss paper (section 4.2, eq. 18-19, Appendix B
// eq. 25-28): per chart, new UVs phi whose per-triangle Jacobians match the triangle
// stage's targets R-bar S-bar up to a 90-degree rotation k_i, by local-global iterations on
//   sum_i  w_R |R_i - R-bar_i R(k_i pi/2)|^2 + w_S |S_i - S-bar_i|^2 + w_rs |grad phi_i - R_i S_i|^2
// (R_i a rotation, S_i symmetric, det grad phi_i > 0), initialized from the input UVs.
//
// Jacobians live in texel space: grad phi_i = [new edges][old edges]^-1, the map from the
// input UVs (texels) to the output UVs (texels); phi = identity at the start.
//
// Local step (per triangle, closed forms): for every k in 0..3, two exact block updates
//   R = polar(w_R R-bar R(k pi/2) + w_rs J S^T)              (exact minimizer of eq. 25)
//   S = (w_S S-bar + w_rs sym(R^T J)) / (w_S + w_rs)           (eq. 26, S^T = S)
// and the k with the lowest energy of eq. 19 is kept; a triangle keeps its current
// (k, R, S) unless the candidate is strictly better, so the local step never raises eq. 19.
// (The paper picks k by |J - R-bar R(k pi/2)|; with w_rs << w_R, w_S the energy picks by
// |J - R-bar R(k pi/2) S-bar|, the same idea with the stretch included.)
//
// Global step: eq. 27, sum w_rs |J_i - R_i S_i|^2 + w_b sum B(det J_i), with the barrier of
// Schueller et al. 2013: B(x) = 1/g(x/s_i) - 1, g(u) = 1 - (1-u)^3, for 0 < x < s_i, 0 for
// x >= s_i (C2), +inf for x <= 0, threshold s_i = barrier_threshold * det S-bar_i. Damped
// Newton: exact Hessian of the fit term, barrier Hessian B'' cof cof^T + |B'| P_anti (its
// indefinite part B' Hess(det) clamped to PSD), on the fixed pattern of
// solve::SparseSystem (vertex 0 pinned: the translation null space), then the maximal
// non-inverting step and Armijo backtracking (solve::max_injective_step, solve::armijo).
// The fit term's matrix depends on the input UVs only and is factorized once per chart:
// with no active barrier the Newton step is one solve with it (exact); with a few active
// barriers, PCG preconditioned by it; with more, a numeric refactorization of the full
// Hessian. After each global step, w_b /= 20 when w_rs E_rs < w_b E_barrier (eq. 28).
// The objective eq. 19 + w_b E_barrier never increases from one iteration to the next.
// With weak stretch weights and rotation targets that disagree with the neighbours', the
// formulation itself favours shrinking a triangle (|J - R S| -> 0 as J, S -> 0; the paper's
// "triangles approach degeneration"): the barrier is what keeps those from collapsing.
//
// Weights: w_R, w_S are floored at max(weight_floor, weight_floor_relative * mean weight of
// the chart); non-finite or negative weights count as 0. Nothing here becomes singular at
// w = 0 (the global matrix is w_rs times a Laplacian-like matrix plus a PSD barrier), the
// floor only keeps flat-signal triangles (w ~ 1e-16) from being pure followers. Note that
// the pull of a triangle toward its target per local-global iteration is about
// w / (w + w_rs): weights far below w_rs converge slowly (see max_iterations).
//
// Triangles whose input UV area is not positive (2A <= 1e-12 * longest edge^2, or clockwise)
// have no Jacobian: they are "passive" - no energy, no barrier, not checked for flips - and
// their vertices move with the rest. Charts should be one connected piece (only vertex 0 is
// pinned). Deterministic: per-triangle loops are OpenMP static with fixed-order sums, and
// CHOLMOD runs with BLAS on one thread (solve::configure_blas_threads).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace uvpress::perceptual {

struct TriangleTarget {
  std::array<double, 4> rotation{1, 0, 0, 1};  // R-bar, row-major
  std::array<double, 4> stretch{1, 0, 0, 1};   // S-bar, symmetric, row-major
  double weight_rotation = 1, weight_stretch = 1;  // w_R, w_S (eq. 17)
};

// How fit_chart ended for a chart.
enum class MeshStageStatus {
  Optimized,            // local-global ran; `uv` is its result (flip-free)
  NoActiveTriangles,    // every triangle is passive: nothing to fit, `uv` = the input
  FactorizationFailed,  // a sparse factorization failed (see MeshStageResult::failure).
                        // The fit term's matrix, at the start: `uv` = the input, untouched.
                        // A full-Hessian refactorization later (many active barriers): `uv` =
                        // the last accepted iterate, flip-free but not converged.
};
const char* to_string(MeshStageStatus s);  // "optimized", "no active triangles", "factorization failed"

struct MeshStageOptions {
  double w_rs = 1e-5;              // eq. 19
  int max_iterations = 100;        // local-global iterations
  double tolerance = 1e-6;         // stop when an iteration lowers the objective by less than this, relatively
  int newton_iterations = 1;       // damped Newton steps per global step (eq. 27); 1 is
                                   // enough for local-global and keeps the objective monotone
  double barrier_weight = 1;       // initial w_b, in units of w_rs
  double barrier_threshold = 0.1;  // s_i = barrier_threshold * det S-bar_i
  double barrier_shrink = 20;      // eq. 28
  double weight_floor = 0;                // absolute floor on w_R, w_S
  double weight_floor_relative = 1e-3;    // floor relative to the chart's mean weight
  // Test hook: the n-th numeric factorization of the chart (1-based, 1 = the fit term's
  // matrix; 0 = none) sees its matrix negated, so CHOLMOD fails on it.
  int test_break_factorization = 0;
};

struct MeshStageResult {
  std::vector<double> uv;       // 2 per vertex, texel units
  MeshStageStatus status = MeshStageStatus::Optimized;
  std::string failure;          // status FactorizationFailed: which matrix and why, e.g. "fit matrix:
                                // factorization failed: matrix not positive definite (CHOLMOD)"; else ""
  bool failed() const { return status == MeshStageStatus::FactorizationFailed; }
  int iterations = 0;           // local-global iterations done
  int newton_steps = 0;         // linear solves in all global steps
  int factorizations = 0;       // numeric factorizations (1: the fit term's matrix, reused)
  int cg_iterations = 0;        // PCG iterations in Newton steps with active barriers
  size_t flips = 0;             // active triangles with det grad phi <= 0 at the end (always 0)
  size_t passive = 0;           // triangles without a usable input UV area
  double energy = 0;            // eq. 19 at the end
  double barrier_weight = 0;    // w_b at the end
  std::vector<int> k;           // per triangle: target rotation R-bar R(k pi/2), k in 0..3
  std::vector<double> jacobian; // per triangle: grad phi_i, 4 row-major (0 for passive ones)
  std::vector<double> objective_history;  // eq. 19 + w_b E_barrier, after each iteration (entry 0: after the first local step)
  std::vector<double> energy_history;     // eq. 19, same points
  // Seconds: local steps; global-step gradients and Hessians; numeric factorizations;
  // solves; line searches and energies.
  double t_local = 0, t_derivatives = 0, t_factorization = 0, t_solve = 0, t_line_search = 0;
};

// One chart: `uv` = input UVs in texel units (2 per vertex), `triangles` 3 per triangle (CCW
// in UV), one target per triangle. Throws std::invalid_argument on mismatched sizes or
// options out of range. A solver failure does not throw: it is the result's status (a
// caller that wants the chart's input layout on failure checks result.failed()).
MeshStageResult fit_chart(const std::vector<double>& uv, const std::vector<uint32_t>& triangles,
                          const std::vector<TriangleTarget>& targets, const MeshStageOptions& options = {});

namespace detail {
// Barrier B(x; s) of the global step and its first two derivatives.
double barrier(double x, double s, double* d1 = nullptr, double* d2 = nullptr);
// Eq. 27 at `uv` for fixed per-triangle targets T_i = R_i S_i (4 per triangle, row-major)
// and thresholds s_i, Jacobians relative to `uv0`; gradient (2 per vertex) when asked.
double global_energy(const std::vector<double>& uv0, const std::vector<uint32_t>& triangles,
                     const std::vector<double>& T, const std::vector<double>& s, double w_rs, double w_b,
                     const std::vector<double>& uv, std::vector<double>* gradient = nullptr);
}  // namespace detail

}  // namespace uvpress::perceptual
