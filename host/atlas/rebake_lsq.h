// Least-squares re-bake: the texels that a renderer's bilinear filter turns into the
// signal closest to the source over the surface (issue 17 item 1; DESIGN.md "Charts,
// packing, re-bake": "the bake that loses least on screen").
//
// rebake() (area filter) gives every new texel the mean of the source over the texel's
// footprint. A renderer then interpolates those texels bilinearly, which blurs a second
// time: rotated or non-integer-scaled charts lose detail twice. This bake instead solves
//
//   E(T) = sum_x ( bilinear(T, new_uv(x)) - S(x) )^2 + mu' sum_edges g_ij (T_i - T_j)^2      (1)
//
// over the new image's texels T, the atlas-scale form of the triangle stage's bake (Sun et
// al. 2022, eq. 11; engine/cpu/view_bake.cpp). The sample points x are a regular k x k grid
// per new texel, kept where they fall inside a new-UV triangle (the first that contains
// them: the texel's owner, else the tile list's order). S(x) is the band-limited source:
// the area filter's own footprint filter (engine::rebake_filter_box, the same n_x by n_y
// bilinear samples through the triangle's barycentric map) applied to a new-texel-sized
// square centred on x; where the layout does not shrink the source (|J e| <= 1) that is the
// plain bilinear source at x's old UV, so an identity layout has the source texels as an
// exact, zero-residual solution. The membrane (second term) only regularizes texels that
// samples constrain weakly: g_ij = max(g_i, g_j), g = 1 - min(1, d / (4 mu')) with d the
// texel's diagonal of the data term's normal matrix (its squared bilinear weights summed
// over the samples) and mu' = mu x samples / unknowns as in view_bake.cpp; a texel with
// d >= 4 mu' (every chart texel, a ring texel along an edge) carries none of its own, so
// interior texels are not biased and an identity layout stays exact.
//
// Unknowns are the texels some kept sample's bilinear footprint touches (covered texels
// and their 1-texel ring, wrapped by the sampler's wrap modes); every other texel keeps
// the area-filtered bake's value, and the gutter is refilled from the nearest unknown (the
// same distance transform as rebake). The normal equations (9-point stencil per unknown)
// are assembled in a fixed order (rows in three interleaved phases) and solved by Jacobi-
// preconditioned conjugate gradients per channel, started from the area-filtered bake (the
// start and the oracle: the result never has a larger objective (1) than it). Reductions
// are in fixed blocks summed in order: the bytes do not depend on the OpenMP thread count.
//
// Colour textures are solved in linear light (rebake's decode/encode tables), straight
// (the target of a texture with alpha is the premultiplied filter divided by alpha, as the
// area bake computes it), alpha as data; data textures as stored; each channel clamped to
// [0, 1] after. Normal maps keep the area-filtered bake (a least-squares fit of unit
// vectors would need the rotation and renormalization inside the objective).
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
  // (1 / k: the fit of bilinear texels to the source itself). Measured as written over 20
  // views at half the texels, the sharper target loses: demo q 0.0333 vs 0.0311, Duck
  // 0.00089 vs 0.00068 (it aliases what the new texels cannot hold).
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
// refill, so a surround (RebakeOptions::surround) survives the solve; without it, every
// texel past the solved ring is refilled from the solved texels. Throws
// std::invalid_argument when area_baked (or keep) does not match options and source.
Image rebake_least_squares(const Image& source, const std::vector<RebakeMesh>& meshes, const RebakeOptions& options,
                           const Image& area_baked, LsqBakeStats* stats = nullptr, const LsqBakeOptions& lsq = {},
                           const std::vector<uint8_t>* keep = nullptr);

}  // namespace uvpress::atlas
