// A triangle mesh as flat arrays (meshoptimizer style). UVs have their own vertices and
// their own triangles, as in OBJ: a UV seam is where two triangles share a position but
// not a UV vertex. For glTF primitives both index arrays are the same.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace uvpress {

struct Mesh {
  std::vector<double> positions;       // x y z per vertex
  std::vector<uint32_t> triangles;     // 3 vertex indices per triangle, counter-clockwise
  std::vector<double> uvs;             // u v per UV vertex; empty when the mesh has none
  std::vector<uint32_t> uv_triangles;  // 3 UV-vertex indices per triangle; empty when no UVs

  size_t vertex_count() const { return positions.size() / 3; }
  size_t triangle_count() const { return triangles.size() / 3; }
  size_t uv_count() const { return uvs.size() / 2; }
  bool has_uvs() const { return !uv_triangles.empty(); }
};

}  // namespace uvpress
