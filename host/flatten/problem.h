// A flatten problem: the mesh's connectivity and its ideal (3-D) reference triangles, on
// which problems (4) and (5) of Liu et al. 2018 measure the symmetric Dirichlet distortion
// (solve/triangle_energy.h) of a UV map.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace uvpress::flatten {

// The fixed part of problems (4) and (5): connectivity and the ideal reference triangles.
struct Problem {
  size_t vertex_count = 0;
  std::vector<uint32_t> triangles;  // 3 per triangle
  std::vector<double> ideal;        // 4 per triangle: Rinv of the 3-D triangle in its own frame
  std::vector<double> area;         // per triangle, mesh scaled to total area 1 (so E/|M| = E)
  double scale = 1;                 // 3-D lengths were multiplied by this to reach area 1
  size_t degenerate = 0;            // triangles whose reference was replaced (see make_problem)
  size_t triangle_count() const { return triangles.size() / 3; }
};

// Builds the ideal references from 3-D positions (x y z per vertex) scaled to total area 1.
// A triangle with 2*area <= 1e-10 * (longest edge)^2 has no usable reference shape: it gets
// an equilateral reference of the mean triangle area and a weight floor (1e-6 of the mean
// area) in problem (5), so that its distortion is finite, it keeps a barrier against
// inversion, and it contributes (almost) nothing to E. No NaN can come out of it.
Problem make_problem(const std::vector<double>& positions, const std::vector<uint32_t>& triangles);

// Area weights of problem (5), with the floor above.
std::vector<double> area_weights(const Problem& p);

}  // namespace uvpress::flatten
