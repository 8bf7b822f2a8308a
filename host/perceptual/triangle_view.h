// Per-triangle views (seed 001, section 4.1.1 and Appendix A): for each triangle an
// orthographic camera along its normal at its barycenter whose view square is the
// triangle's bounding square in its own plane (R = (a - C)/|a - C|, U = N x R), or square
// patches of it for triangles too large in texels, and the triangle with its one-ring
// (every triangle sharing a vertex position) in view space.
#pragma once

#include "core/image.h"
#include "engine.h"

#include <cstdint>
#include <vector>

namespace uvpress::perceptual {

struct TriangleViewInput {
  const float* positions = nullptr;  // x y z per vertex
  size_t vertex_count = 0;
  const uint32_t* indices = nullptr;  // 3 per triangle
  size_t triangle_count = 0;
  const float* uvs = nullptr;        // u v per vertex (glTF convention: v down the image)
  uint32_t texture_width = 0, texture_height = 0;
};

// The views of a set of triangles, with what the triangle stage needs to combine them.
struct TriangleViews {
  engine::ViewSetDesc desc;             // every view, triangle after triangle
  std::vector<uint32_t> first_view;     // per requested triangle, plus one: its views are [first_view[k], first_view[k + 1])
  std::vector<float> texels_per_pixel;  // per view: the largest singular value of its own triangle's screen-to-texel map
  std::vector<uint8_t> complete;        // per requested triangle: 1 when its views cover its whole bounding square
};

// Views of `which` triangles (all when empty), S = `size` pixels a side.
//
// Resolution. The loss of eq. 5-7 is only the paper's when the view resolves the source
// texels (texels_per_pixel <= 1): a view that minifies them compares aliasing, and the
// identity J would no longer be lossless. The paper's single view (the triangle's bounding
// square at S pixels) does that for triangles up to S texels across; a larger triangle is
// instead seen through square patches of its bounding square, n x n of them with
// n = ceil(texels across / S), so each patch again resolves its texels. Views cost pixels
// and tile texels, so at most `max_patches` patches whose centre lies in the triangle are
// kept, spread evenly over it (`complete` says when some were left out); the triangle
// stage combines a triangle's views as the RMS of their GMSD.
//
// Seams. Ring triangles are grouped by chart (shared vertices with equal UVs); a
// neighbour across a UV seam keeps its own UVs for the reference render and gets its own
// region of the candidate tile, with J applied about the seam vertex it shares with the
// view's triangle (ViewTriangle::anchor_s, anchor_t). At most kViewMaxGroups groups: any
// further chart joins the last group.
//
// Ring triangles that reach past the guard band are clipped to it (their attribute planes
// are unchanged by clipping); rings longer than kViewMaxTriangles keep the triangles
// nearest the centre. Degenerate triangles (zero area in space) get a view with no pixels.
// The texture pointer of the result is left for the caller to set.
//
// `min_texels_per_pixel` (0: the paper's view, the triangle's bounding square): a triangle
// so small that its view would magnify its texels beyond this (e.g. 0.5: two pixels a
// texel) is seen through a larger square about the same centre instead. GMSD compares
// gradients against a fixed constant, so a view that spreads each texel over many pixels
// flattens every gradient and scores a blur of the texture as nearly lossless; a view at
// a fixed magnification scores a triangle as a screen would, whatever its size.
TriangleViews make_triangle_views(const TriangleViewInput& input, uint32_t size,
                                  const std::vector<uint32_t>& which = {}, uint32_t max_patches = 4,
                                  double min_texels_per_pixel = 0);

}  // namespace uvpress::perceptual
