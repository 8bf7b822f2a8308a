// Per-triangle views (seed 001, section 4.1.1 and Appendix A): for each triangle an
// orthographic camera along its normal at its barycenter whose view square is the
// triangle's bounding square in its own plane (R = (a - C)/|a - C|, U = N x R), and the
// triangle with its one-ring (every triangle sharing a vertex position) in view space.
#pragma once

#include "core/image.h"
#include "engine.h"

#include <cstdint>
#include <vector>

namespace uvpress::perceptual {

// GMSD step 1 on a decoded texture: Y = 0.299 R + 0.587 G + 0.114 B on the stored values
// (grey images: the value itself; alpha ignored).
std::vector<float> luminance_plane(const Image& image);

struct TriangleViewInput {
  const float* positions = nullptr;  // x y z per vertex
  size_t vertex_count = 0;
  const uint32_t* indices = nullptr;  // 3 per triangle
  size_t triangle_count = 0;
  const float* uvs = nullptr;        // u v per vertex (glTF convention: v down the image)
  uint32_t texture_width = 0, texture_height = 0;
};

// Views of `which` triangles (all when empty), S pixels a side. Ring triangles that reach
// past the guard band are clipped to it (their attribute planes are unchanged by
// clipping); rings longer than kViewMaxTriangles keep the triangles nearest the centre.
// Degenerate triangles (zero area in space) get a view with no pixels. The texture
// pointer of the result is left for the caller to set.
engine::ViewSetDesc make_triangle_views(const TriangleViewInput& input, uint32_t size,
                                        const std::vector<uint32_t>& which = {});

}  // namespace uvpress::perceptual
