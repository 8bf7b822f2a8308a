// The mesh-wise stage of the perceptual-loss paper (section 4.2, eq. 18-19, Appendix B
// eq. 25-28): per chart, new UVs phi whose per-triangle Jacobians match the triangle
// stage's targets R-bar S-bar up to a 90-degree rotation k_i, by local-global iterations on
//   sum_i  w_R |R_i - R-bar_i R(k_i pi/2)|^2 + w_S |S_i - S-bar_i|^2 + w_rs |grad phi_i - R_i S_i|^2
// (R_i a rotation, S_i symmetric, det grad phi_i > 0), initialized from the input UVs.
// Jacobians live in texel space: grad phi_i = [new edges][old edges]^-1, the map from the
// input UVs (texels) to the output UVs (texels); phi = identity at the start. A barrier
// (Schueller et al. 2013) keeps the triangles from flipping, the objective never increases
// from one iteration to the next, and the result is deterministic. The local and global
// steps, the barrier and the weights: the top of mesh_stage.cpp.
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
// in UV), one target per triangle. The chart should be one connected piece (only vertex 0
// is pinned). Triangles without a usable input UV area are passive (no energy, not checked
// for flips; their vertices move with the rest). Throws std::invalid_argument on mismatched
// sizes or options out of range. A solver failure does not throw: it is the result's status
// (a caller that wants the chart's input layout on failure checks result.failed()).
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
