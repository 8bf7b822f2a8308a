// Overlapping triangles in UV space: the injectivity check every written layout passes.
//
// Two triangles overlap when their interiors share a region of positive area. Touching
// along an edge or at a vertex is not an overlap (neighbours in a chart always touch), a
// fold (two triangles on the same side of their shared edge), a triangle inside another,
// crossing edges and coincident or mirrored duplicates are. Degenerate triangles (zero
// area) have no interior and overlap nothing. The test is exact: orientation signs from an
// error-free expansion of the 2x2 determinant (a floating-point filter first, the exact sum
// only when the filter cannot tell), so collinear and shared-vertex cases are decided
// right, never by a tolerance.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace uvpress::atlas {

using TrianglePair = std::array<uint32_t, 2>;  // triangle indices, first < second

// Sign of the orientation of (a, b, c): +1 counter-clockwise (in x-right, y-up axes), -1
// clockwise, 0 collinear. Exact for any finite doubles whose products do not overflow.
int orientation(const double a[2], const double b[2], const double c[2]);

// Whether triangles (a0, a1, a2) and (b0, b1, b2) overlap with positive area, in either
// orientation. Separating axes: the interiors are disjoint exactly when one triangle lies
// in the closed outer half-plane of an edge of the other (the edges of the Minkowski
// difference of two triangles are parallel to theirs), 18 exact orientation tests at most.
bool triangles_overlap(const double a0[2], const double a1[2], const double a2[2], const double b0[2],
                       const double b1[2], const double b2[2]);

// Every pair of overlapping triangles of a soup (points: x y per vertex; triangles: 3
// indices each), sorted. Triangles are bucketed by bounding box into a uniform grid of
// about one cell per triangle (cells the size of the mean box, at least), and a pair is
// tested only in the one cell holding the lower corner of its boxes' intersection, so each
// candidate is tested once. Serial and deterministic.
std::vector<TrianglePair> find_overlaps(const double* points, const uint32_t* triangles, size_t triangle_count);

// The overlaps a new layout adds: pairs overlapping under `after` that did not under
// `before` (the same triangles, each point array indexed by `triangles`). Pairs the input
// already had (mirrored halves, instanced parts sharing texels, folds) are not counted.
std::vector<TrianglePair> find_new_overlaps(const double* before, const double* after, const uint32_t* triangles,
                                            size_t triangle_count);

}  // namespace uvpress::atlas
