// The limits on a view set that every backend shares (shaders/layout.h).
#include "backend.h"

#include <cmath>
#include <string>

namespace uvpress::engine {

void check_view_set(const ViewSetDesc& d) {
  if (d.size < 8 || d.size > shader::kViewMaxSize || d.size % 2)
    throw EngineError("view size " + std::to_string(d.size) + " is not an even number in 8..64");
  if (!d.texture || d.texture_width == 0 || d.texture_height == 0) throw EngineError("views need a texture");
  for (const ViewDesc& v : d.views) {
    if (v.triangle_count == 0 || v.triangle_count > shader::kViewMaxTriangles ||
        uint64_t(v.first_triangle) + v.triangle_count > d.triangles.size())
      throw EngineError("a view's triangle range is empty, too long or outside the triangle array");
    if (v.group_count < 1 || v.group_count > shader::kViewMaxGroups)
      throw EngineError("a view's group count is not in 1..kViewMaxGroups");
    for (uint32_t k = 0; k < v.triangle_count; ++k) {
      const ViewTriangle& t = d.triangles[v.first_triangle + k];
      for (float c : t.xy)
        if (!(std::abs(c) <= float(shader::kViewGuardBand)))
          throw EngineError("a view triangle lies outside the guard band (clip it on the host)");
      // Bounded texel gradients and offsets keep every candidate footprint finite, so the
      // tile layout's coarsening ends (shaders/layout.h).
      const float m = float(shader::kViewMaxTexelsPerPixel);
      if (!(std::abs(t.s[1]) <= m && std::abs(t.s[2]) <= m && std::abs(t.t[1]) <= m && std::abs(t.t[2]) <= m &&
            std::abs(t.s[0]) <= 1e7f && std::abs(t.t[0]) <= 1e7f && std::abs(t.anchor_s) <= 1e7f &&
            std::abs(t.anchor_t) <= 1e7f && t.group < v.group_count))
        throw EngineError("a view triangle maps more than kViewMaxTexelsPerPixel texels to a pixel, or has a bad group");
    }
  }
}

}  // namespace uvpress::engine
