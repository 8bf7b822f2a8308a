// Whole-mesh renders, the part both backends share: triangle set-up and binning (host
// code, double precision, made once per view). The per-pixel shading of a tile is the CPU
// backend's (cpu/render_mesh.cpp, shade_tile), which render_mesh.comp mirrors operation
// for operation.
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

// Where camera c's image lies in a render's pixels (MeshRenderDesc::view_tiles_x/y): the
// index of its pixel (0, 0) and the pixels a row of its view holds; with
// MeshRenderDesc::halve, of its halved image in the halved view (pixel (i, j) of the camera
// at (i / 2, j / 2) from the origin).
struct ImagePlace {
  size_t origin = 0, row_stride = 0;
};
ImagePlace image_place(const MeshRenderDesc& d, uint32_t c);

ViewSetup setup_view(const MeshRenderDesc& d, uint32_t view);

}  // namespace uvpress::engine::mesh
