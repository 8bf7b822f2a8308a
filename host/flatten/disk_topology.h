// Is a triangle mesh a topological disk? One connected component, every edge shared by at
// most two consistently oriented triangles, every vertex a single fan, exactly one
// boundary loop and Euler characteristic 1 (genus 0). The checks a parameterization needs
// before Tutte's embedding can be trusted to be bijective.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace uvpress::flatten {

struct DiskTopology {
  // Compact numbering: the input vertices that some triangle uses, in input order.
  std::vector<uint32_t> used_vertices;     // compact -> input vertex
  std::vector<uint32_t> triangles;         // 3 per triangle, compact vertex indices
  std::vector<uint32_t> boundary;          // the boundary loop, compact indices, in the
                                           // direction of the triangles' boundary edges
};

// Throws FlattenError with a message that names every reason the mesh is not a disk:
// repeated vertices in a triangle, non-manifold edges (> 2 triangles), inconsistent
// orientation, non-manifold vertices, the number of components, of boundary loops, genus.
DiskTopology check_disk(const std::vector<uint32_t>& triangles, size_t vertex_count);

}  // namespace uvpress::flatten
