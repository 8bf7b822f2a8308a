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

// Holes filled virtually: every boundary loop but the longest (in 3-D length) closed by a
// temporary vertex at the loop's centroid and a fan of triangles to it, so that a chart
// with holes becomes a disk. The temporary vertices follow the input's (ids from
// positions.size() / 3 on), the fan triangles follow its triangles: drop both after
// flattening. Nothing is added when the boundary is not a set of simple loops (a
// non-manifold edge or vertex, inconsistent orientation): check_disk then says why.
struct FilledHoles {
  std::vector<double> positions;    // input positions, then one per filled loop
  std::vector<uint32_t> triangles;  // input triangles, then the fans
  size_t filled_loops = 0;
};
FilledHoles fill_holes(const std::vector<double>& positions, const std::vector<uint32_t>& triangles);

}  // namespace uvpress::flatten
