// Charts: the connected pieces of a UV layout. Two triangles are in one chart when they
// share a UV vertex; a UV seam is where they share a position but not a UV vertex.
#pragma once

#include "core/mesh.h"

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

}  // namespace uvpress::atlas
