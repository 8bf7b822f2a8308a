// A reshaped chart that keeps its input outline, so that it packs as well as the input did.
//
// The mesh stage (mesh_stage.h) gives each triangle the size and shape the triangle stage
// asked for, but nothing holds the chart's boundary: the flat parts shrink, the detailed
// parts grow, and the outline bulges. The paper counts cost in texels under the charts
// (eq. 20), which cannot see that; a user pays for the whole image, and an irregular outline
// packs badly (the demo's square chart: 95 % of the image under it as input, 56 % reshaped,
// so the reshaped layout had 42 % fewer texels under it at the same image cost).
//
// keep_outline re-embeds the mesh stage's result with its boundary on the input's outline,
// scaled to the result's area: each boundary loop's corners (turns sharper than
// `corner_degrees`) stay at their scaled input positions, the vertices between two corners
// slide along the input's side to the fractions of arc length they have on the result's
// boundary, and the interior solves the Poisson problem
//   min_u sum_t A_t |grad u_t - J_t|^2   (u fixed on the boundary)
// for the result's own Jacobians J_t (relative to the input UVs, after taking out the
// result's overall rotation, which the outline could not follow without losing its axis
// alignment). Where the solve folds a triangle, the Jacobians are blended toward the uniform
// scale (half, then all the way: the input shape scaled), which cannot fold.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace uvpress::perceptual {

struct OutlineOptions {
  double corner_degrees = 20;  // a boundary vertex whose outline turns more than this is pinned
};

struct OutlineFit {
  std::vector<double> uv;  // 2 per vertex, texel units
  double blend = 0;        // 0: the result's Jacobians; 0.5: halfway to uniform; 1: the input scaled
  std::string failure;     // why no re-embedding was made ("" on success; uv is then the result as given)
  bool ok() const { return failure.empty(); }
};

// `uv0`: the chart's input UVs, `uv1`: the mesh stage's result (2 per vertex, texel units),
// `triangles`: 3 local indices per triangle, counter-clockwise in uv0. The chart must be one
// connected piece whose boundary edges form closed loops (a disk or a disk with holes).
OutlineFit keep_outline(const std::vector<double>& uv0, const std::vector<double>& uv1,
                        const std::vector<uint32_t>& triangles, const OutlineOptions& options = {});

}  // namespace uvpress::perceptual
