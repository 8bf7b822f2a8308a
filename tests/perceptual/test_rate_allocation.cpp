// The equal-slope allocation (host/perceptual/rate_allocation.h) against known optima.
#include <catch2/catch.hpp>

#include "perceptual/rate_allocation.h"

#include <cmath>

using namespace uvpress;
using perceptual::LossCurves;

namespace {

// Loss measured at `scales` from g(s).
template <class F>
void add(LossCurves& c, F g) {
  for (double s : c.scales) c.loss.push_back(g(s));
}

}  // namespace

TEST_CASE("equal slope: two linear losses split the budget as the Lagrangian says", "[perceptual][rate]") {
  // g1 = 1 - s, g2 = 0.5 (1 - s), equal areas and weights: w g'(s) = -2 mu a s gives
  // s1 = 2 s2; at c = 0.25, s1^2 + s2^2 = 0.5: s2 = sqrt(0.1) = 0.316, s1 = 0.632.
  LossCurves c;
  c.scales = {0.1, 0.25, 0.5, 0.75, 1.0};
  add(c, [](double s) { return 1 - s; });
  add(c, [](double s) { return 0.5 * (1 - s); });
  const auto r = perceptual::allocate_by_equal_slope(c, {1, 1}, {1, 1}, 0.25, 0.05, 400);
  CHECK(r.scale[0] == Approx(0.632).margin(0.01));
  CHECK(r.scale[1] == Approx(0.316).margin(0.01));
  CHECK(r.spent <= 0.25 + 1e-12);
  CHECK(r.spent > 0.24);
  // Twice the weight on the second: the split reverses.
  const auto w = perceptual::allocate_by_equal_slope(c, {1, 1}, {1, 4}, 0.25, 0.05, 400);
  CHECK(w.scale[1] > w.scale[0]);
}

TEST_CASE("equal slope: a loss that saturates keeps its texels, a gentle one gives them up", "[perceptual][rate]") {
  // Noise-like: everything is lost by 0.85 (the resize already loses it), nothing at 1.
  // Smooth: loses little at any scale. A bound relative to the resize's loss lets the first
  // shrink to the floor; the budget is better spent keeping it whole.
  LossCurves c;
  c.scales = {0.125, 0.25, 0.5, 0.707, 0.85, 1.0};
  add(c, [](double s) { return s < 1 ? 0.2 : 0.0; });
  add(c, [](double s) { return 0.02 * (1 - s); });
  const auto r = perceptual::allocate_by_equal_slope(c, {1, 1}, {1, 1}, 0.55);
  CHECK(r.scale[0] == Approx(1.0));
  CHECK(r.scale[1] < 0.4);
  CHECK(r.spent <= 0.55);
  // All the budget there is: both whole.
  const auto all = perceptual::allocate_by_equal_slope(c, {1, 1}, {1, 1}, 1.0);
  CHECK(all.scale[0] == 1.0);
  CHECK(all.scale[1] == 1.0);
  CHECK(all.multiplier == 0.0);
}

TEST_CASE("equal slope: a noisy dip in a measured loss buys no texels back", "[perceptual][rate]") {
  // The first curve reads 0 at 0.5 (noise) but 0.3 at 0.25 and 0.75: taken as measured, 0.5
  // would be a free lunch. Made non-increasing in s it is 0.3 up to 0.75, so the triangle
  // needs more than 0.75 to gain anything, and the budget (0.6) is there for it.
  LossCurves c;
  c.scales = {0.25, 0.5, 0.75, 1.0};
  c.loss = {0.3, 0.0, 0.3, 0.0,   //
            0.02, 0.01, 0.005, 0.0};
  const auto r = perceptual::allocate_by_equal_slope(c, {1, 1}, {1, 1}, 0.6);
  CHECK(r.scale[0] > 0.75);
  CHECK(r.scale[1] < r.scale[0]);
  CHECK(r.spent <= 0.6);
}
