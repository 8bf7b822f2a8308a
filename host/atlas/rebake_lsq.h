// Least-squares re-bake (issue 17 item 1; DESIGN.md "Charts, packing, re-bake": "the bake
// that loses least on screen"): the new texels T that a renderer's bilinear filter turns
// into the signal closest to the band-limited source S over the surface, minimizing
//
//   E(T) = sum_x ( bilinear(T, new_uv(x)) - S(x) )^2 + mu' sum_edges g_ij (T_i - T_j)^2      (1)
//
// over sample points x inside the new-UV triangles (the atlas-scale form of the triangle
// stage's bake, Sun et al. 2022, eq. 11). Started from the area-filtered bake, and never
// worse than it under (1); texel units; the same bytes whatever the thread count. How the
// samples, targets and membrane weights are chosen and (1) is solved: the top of
// rebake_lsq.cpp.
#pragma once

#include "atlas/rebake.h"

#include <cstddef>
#include <cstdint>

namespace uvpress::atlas {

struct LsqBakeOptions {
  uint32_t samples_per_axis = 4;  // k: sample points per new texel and axis (rounded up to even, >= 2)
  double mu = 1e-4;               // membrane weight relative to the samples per unknown (view_bake's kSmoothness)
  uint32_t max_iterations = 400;  // conjugate-gradient iterations (all channels in lockstep)
  double tolerance = 1e-7;        // stop a channel at ||b - A T|| <= tolerance ||b||
  // Side of the square, in new texels, over which the source is averaged for each sample's
  // target: 1 = a whole new texel (the area filter's band limit), 0 = the sample's own cell
  // (1 / k: the fit of bilinear texels to the source itself; measured worse, rebake_lsq.cpp).
  double target_cell = 1;
};

struct LsqBakeStats {
  bool solved = false;          // false: the area bake was returned (normal map, nothing covered)
  uint32_t iterations = 0;      // conjugate-gradient iterations (the slowest channel)
  double initial_residual = 0;  // ||b - A T|| / ||b|| over all channels, at the area bake
  double final_residual = 0;    // the same at the result (before the [0, 1] clamp)
  double initial_objective = 0; // E(T) of (1) at the area bake, all channels (working space)
  double final_objective = 0;   // E(T) at the result (before the clamp)
  size_t samples = 0;           // sample points inside triangles
  size_t unknowns = 0;          // texels solved for
  double seconds = 0;           // the whole call
};

// The least-squares bake of `source` into the layout `meshes` describe, as rebake() would
// bake it with `options` (size, role, wrap modes, linear light); `area_baked` is rebake()'s
// result for the same arguments, or rebake_lanczos()'s (the start, and the values of every
// texel that is not solved for). Returns an image like area_baked (same size, channels,
// bits). `keep`, when given (width * height, as rebake_lanczos's `baked` with a surround):
// texels marked 1 that are not solved for keep area_baked's values through the gutter
// refill, so a surround (RebakeOptions::surround) survives the solve, and the fill continues
// it as rebake_lanczos's does (atlas::fill_ring); without it, every texel past the solved
// ring is refilled from the solved texels (a one-texel ring). Normal maps get area_baked
// back (stats->solved false). Throws std::invalid_argument when area_baked (or keep) does
// not match options and source.
Image rebake_least_squares(const Image& source, const std::vector<RebakeMesh>& meshes, const RebakeOptions& options,
                           const Image& area_baked, LsqBakeStats* stats = nullptr, const LsqBakeOptions& lsq = {},
                           const std::vector<uint8_t>* keep = nullptr);

}  // namespace uvpress::atlas
