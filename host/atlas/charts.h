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

// One chart as a mesh of its own: its triangles (ids into the mesh, ascending), its vertices
// (the mesh's UV vertex ids, numbered in the order its triangles first use them; a UV
// vertex belongs to one chart) and, per triangle, three indices into those vertices.
struct ChartMesh {
  std::vector<uint32_t> triangles;
  std::vector<uint32_t> uv_vertices;
  std::vector<uint32_t> corners;  // 3 per triangle, into uv_vertices
};

// Every chart of `charts` (found on `mesh`) as a ChartMesh, in chart order, in one pass.
std::vector<ChartMesh> split_charts(const Mesh& mesh, const Charts& charts);

// The chart's surface as a Mesh to flatten: per chart vertex the position of its UV vertex,
// the corners as triangles, no UVs.
Mesh chart_surface(const Mesh& mesh, const ChartMesh& chart);

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

// Charts' UVs (2 per vertex, one array a chart, any common unit) moved in place onto
// shelves by shelf_layout of their bounding boxes, with a gap of 1 % of sqrt(sum of box
// areas); returns the extent (width, height). Flatten's new UV set and eval's isometric
// baseline lay out their flattened charts this way.
std::array<double, 2> shelve_charts(std::vector<std::vector<double>*>& chart_uvs);

}  // namespace uvpress::atlas
