// Step size, paper §3.6 "Step size": the maximal non-inverting step of Smith & Schaefer
// 2015 (per triangle, the smallest positive root of det(P + a dP) = 0, a quadratic in a),
// then Armijo backtracking from a0 = min(1, 0.9 a_max), halving, c = 0.2 (the authors'
// constant). Every accepted iterate is foldover-free: a < a_max keeps every det J > 0, and
// an energy that comes out non-finite is rejected like an insufficient decrease.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

namespace uvpress::solve {

// min over triangles of the first a > 0 at which the triangle degenerates; +inf if none.
double max_injective_step(const std::vector<uint32_t>& triangles, const std::vector<double>& uv,
                          const std::vector<double>& d);

struct LineSearchResult {
  double step = 0;     // 0 when no step decreased the energy enough (strictly, and by Armijo's c a slope)
  double energy = 0;   // objective at the accepted point (the old one when step = 0)
};

// Moves uv to uv + step d. `energy(x)` evaluates the objective (+inf when a triangle is
// inverted); `e0` and `slope` = grad . d (< 0) are the objective and derivative at uv.
LineSearchResult armijo(std::vector<double>& uv, const std::vector<double>& d, double e0, double slope, double a0,
                        const std::function<double(const std::vector<double>&)>& energy);

}  // namespace uvpress::solve
