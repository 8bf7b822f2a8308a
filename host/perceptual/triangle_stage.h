// The triangle-wise optimization of the perceptual-loss paper (section 4.1.2, eq. 12-14,
// weights eq. 17): for every triangle, Bayesian optimization of its Jacobian
//   J = R(alpha) V(beta) diag(lambda1, lambda2) V(beta)^T,
//   alpha, beta in [0, pi/2), lambda in [lambda_min, 1]   (the 90-degree symmetries)
// minimizing lambda1 lambda2 |T| + L_eps(GMSD), L_eps(x) = -log(eps - x), infinite for
// x >= eps, with |T| the triangle's area in source texels. All triangles advance in
// lockstep, one candidate each per round, scored by the engine in one batch.
//
// The barrier never reaches the GP: the GP models z = log(GMSD + 1e-5), which is smooth
// and finite, and the acquisition is the expected improvement of the true objective
// under that posterior (Gauss-Hermite quadrature over z), in which outcomes with
// GMSD >= eps improve nothing. Until a feasible point is known it maximizes the
// probability of feasibility; the first initial point is the identity, whose loss is
// measured like any other: on faithful views it is 0 up to fp32, but a triangle whose
// identity still scores >= eps (or that never finds a point below eps) is returned at the
// identity with `feasible` false and its measured loss.
#pragma once

#include "engine.h"
#include "perceptual/triangle_view.h"

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace uvpress::perceptual {

struct TriangleStageOptions {
  uint32_t view_size = 64;     // S, pixels a view side (the paper's 64)
  uint32_t max_patches = 4;    // views of a triangle too large to resolve in one (triangle_view.h)
  double min_texels_per_pixel = 0;  // small triangles' views magnify no more than this (triangle_view.h; 0: the paper's)
  double epsilon = 0.01;       // GMSD bound (eq. 12)
  // Rate control: one bound per triangle of the mesh (indexed by triangle, overriding
  // `epsilon` when not empty), e.g. a little above the loss a plain resize would cause.
  std::vector<double> epsilons;
  // When in (lambda_min, 1): the second initial point is J = start_scale I (the resize's
  // uniform shrink), so the search holds a known point near its bound from the start.
  double start_scale = 0;
  int evaluations = 100;       // per triangle, initial design included (the paper's budget)
  int initial = 10;
  // Leave the batch when the best objective stalls: at least kStallMinimum evaluations, then
  // kStallWindow without a 0.1 % improvement (triangle_stage.cpp); `evaluations` stays the
  // cap. On by default since the written layouts are as good on screen (DEVELOPERS.md,
  // "The triangle stage's stop rule"); false runs the whole budget, the paper's 100.
  bool early_stop = true;
  double lambda_min = 0.05;
  uint32_t wave = 2048;        // triangles optimized together (bounds memory)
  int weight_samples = 8;      // per weight of eq. 17
  uint64_t seed = 1;
  // Two half-batches in flight, the host proposing while the engine scores. Only pays when
  // the engine has its own processor: on the CPU backend and lavapipe both halves would
  // share the same cores, so `auto` overlaps on GPUs only.
  enum class Overlap { Auto, On, Off } overlap = Overlap::Auto;
  // Called after every round with (triangles finished, triangles in all).
  std::function<void(size_t, size_t)> progress;
};

struct TriangleResult {
  double alpha = 0, lambda1 = 1, lambda2 = 1, beta = 0;
  std::array<double, 4> jacobian{1, 0, 0, 1};  // row-major, texel space
  std::array<double, 4> rotation{1, 0, 0, 1};  // R-bar
  std::array<double, 4> stretch{1, 0, 0, 1};   // S-bar
  bool feasible = false;   // some evaluation met GMSD < eps; else J is the identity, unreshaped
  double gmsd = 0;         // measured at the returned J (RMS over the triangle's views)
  double objective = 0;    // lambda1 lambda2 |T| + L_eps(gmsd); infinite when not feasible
  double identity_gmsd = 0;     // measured at J = I (0 up to fp32 when the views are faithful)
  double identity_lattice = 1;  // candidate tile spacing at J = I: 1 unless the tile had to be coarsened
  double texels_per_pixel = 0;  // the largest over its views: <= 1 when they resolve the source texels
  int views = 1;                // views scored per evaluation (patches of a large triangle)
  bool complete = true;         // the views cover the whole triangle (false: a sample of patches)
  double texel_area = 0;   // |T|
  int evaluations = 0;
  double weight_rotation = 0, weight_stretch = 0;  // w_R, w_S (eq. 17)
};

struct TriangleStageStats {
  double host_seconds = 0;    // proposing and updating
  double device_seconds = 0;  // inside the engine's scoring calls
  double wall_seconds = 0;
  size_t evaluations = 0;   // per-triangle evaluations (a triangle's views count once)
  size_t view_scores = 0;   // views scored by the engine
  size_t views = 0;         // views prepared
  size_t rounds = 0;
};

// J for a point of the unit box (alpha, lambda1, lambda2, beta mapped to their ranges).
std::array<double, 4> jacobian_of(const double x[4], double lambda_min, double* alpha = nullptr,
                                  double* lambda1 = nullptr, double* lambda2 = nullptr, double* beta = nullptr);

// The loss of `triangles` (all when empty) at one fixed Jacobian (texel space, row-major),
// measured on the views the triangle stage uses and combined the same way (RMS over a
// triangle's views): e.g. J = I (should be ~0) or J = 0.5 I (what halving costs).
std::vector<double> measure_triangles(engine::Engine& engine, const TriangleViewInput& input,
                                      const std::vector<float>& texture, const TriangleStageOptions& options,
                                      const std::array<double, 4>& jacobian, const std::vector<uint32_t>& triangles = {});
// The same at several Jacobians (result [jacobian][triangle]): the views are set up once and
// every Jacobian scored in one batch; the numbers are those of one call per Jacobian.
std::vector<std::vector<double>> measure_triangles(engine::Engine& engine, const TriangleViewInput& input,
                                                   const std::vector<float>& texture, const TriangleStageOptions& options,
                                                   const std::vector<std::array<double, 4>>& jacobians,
                                                   const std::vector<uint32_t>& triangles = {});

// Optimizes `triangles` (all when empty) of the mesh in `input`, sampling `texture`
// (luminance, input.texture_width x texture_height). Deterministic for a given seed,
// whatever the thread count and the engine.
std::vector<TriangleResult> optimize_triangles(engine::Engine& engine, const TriangleViewInput& input,
                                               const std::vector<float>& texture,
                                               const TriangleStageOptions& options,
                                               const std::vector<uint32_t>& triangles = {},
                                               TriangleStageStats* stats = nullptr);

}  // namespace uvpress::perceptual
