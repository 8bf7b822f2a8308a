// Charts: the connected pieces of a UV layout. Two triangles are in one chart when they
// share a UV vertex; a UV seam is where they share a position but not a UV vertex.
#pragma once

#include "core/mesh.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace uvpress::atlas {

struct Charts {
  uint32_t count = 0;
  std::vector<uint32_t> chart_of_triangle;  // 0 .. count-1, numbered in triangle order
};

// Components of mesh.uv_triangles (the mesh must have UVs).
Charts find_charts(const Mesh& mesh);

// A Mesh for charting from glTF-style arrays (one index for position and UV). glTF
// exporters split vertices for normals and tangents too, so vertices with an identical
// position and UV are welded first: only real UV seams separate charts.
Mesh weld_uv_mesh(const float* positions, const float* uvs, size_t vertex_count, const uint32_t* indices,
                  size_t index_count);

// Boxes (charts' bounding boxes, any units) laid out on shelves at one scale: tallest first
// (ties in input order), left to right, a new shelf when the next box would pass the width
// max(widest box, 1.1 sqrt(sum of box areas)); `gap` around and between boxes. Sets each
// box's lower corner (x, y) and returns the extent (width, height), outer gaps included.
// The quick layout of flattened charts (flatten's new UV set, eval's isometric baseline);
// reparam packs the charts' footprints instead (atlas/pack.h).
struct ShelfBox {
  double w = 0, h = 0;  // size
  double x = 0, y = 0;  // placed lower corner
};
std::array<double, 2> shelf_layout(std::vector<ShelfBox>& boxes, double gap);

}  // namespace uvpress::atlas
