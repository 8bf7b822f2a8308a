// Texel density by equal slopes: how many texels each triangle gets when a budget is split
// to lose least in all.
//
// The triangle stage's targets (eq. 12) are the smallest Jacobians whose loss stays under a
// bound; under rate control that bound is a little above the loss the plain resize causes
// (pipeline/reparam.h). Where a triangle's loss saturates as it shrinks (noise, fine print:
// once the resize has lost it, shrinking further loses little more), that rule lets it
// shrink to the floor, and the texels go to triangles whose loss grows gently. The budget
// is better spent where a texel buys the most loss back: minimize
//
//   sum_t w_t g_t(s_t)   subject to   sum_t a_t s_t^2 = c sum_t a_t
//
// over per-triangle isotropic scales s_t (J = s_t I, source density 1), with g_t the
// triangle's measured loss at a few scales (linear in between, made non-increasing in s),
// a_t its area in source texels and w_t its weight on screen. With a multiplier mu each
// triangle independently takes argmin_s w_t g_t(s) + mu a_t s^2 over a fine grid of
// scales; mu is bisected until the budget is met (the Lagrangian's equal marginal loss per
// texel). Deterministic.
#pragma once

#include <cstddef>
#include <vector>

namespace uvpress::perceptual {

struct LossCurves {
  std::vector<double> scales;  // increasing, in (0, 1]; the loss at scale 1 is taken as measured
  std::vector<double> loss;    // per triangle, scales.size() values (triangle-major)
};

struct RateAllocation {
  std::vector<double> scale;  // per triangle
  double multiplier = 0;      // mu at the solution
  double spent = 0;           // sum a_t s_t^2 / sum a_t
};

// `area` (a_t > 0) and `weight` (w_t >= 0) per triangle; `cost` in (0, 1]: the budget as a
// share of the source's texels under these triangles. Scales are chosen on a grid from
// min_scale to 1 (`steps` values, geometric).
RateAllocation allocate_by_equal_slope(const LossCurves& curves, const std::vector<double>& area,
                                       const std::vector<double>& weight, double cost, double min_scale = 0.1,
                                       size_t steps = 48);

}  // namespace uvpress::perceptual
