// Whole-mesh renders, the parts both backends share: triangle set-up and binning (host
// code, double precision, made once per view) and the per-pixel shading of one tile that
// render_mesh.comp mirrors operation for operation.
#pragma once

#include "engine.h"
#include "layout.h"

#include <cstdint>
#include <vector>

namespace uvpress::engine::mesh {

using shader::MeshTriangle;

// Screen positions farther than this outside the image drop the triangle (it keeps the
// integer edge functions in int32 for images up to kMaxSide). Eval cameras frame the whole
// bounding sphere, so they never drop one.
constexpr int32_t kGuardBand = 256;
constexpr uint32_t kMaxSide = kMeshRenderMaxSide;
// Nearest w a vertex may have; a triangle with a vertex nearer (or behind) is dropped.
constexpr double kNearW = 1e-6;

struct ViewSetup {
  std::vector<MeshTriangle> triangles;  // kept triangles, increasing index
  std::vector<uint32_t> bin_offsets;    // tiles_x * tiles_y + 1
  std::vector<uint32_t> bin_items;      // indices into `triangles`
};

uint32_t tiles_x(const MeshRenderDesc& d);
uint32_t tiles_y(const MeshRenderDesc& d);

ViewSetup setup_view(const MeshRenderDesc& d, uint32_t view);

// Shades tile (tx, ty) of one view: writes coverage and pixels of the view's image (the
// full width x height image of this view, not the batch).
void shade_tile(const MeshRenderDesc& d, const ViewSetup& setup, uint32_t tx, uint32_t ty, uint32_t* coverage,
                float* pixels);

}  // namespace uvpress::engine::mesh
