// Tutte's embedding (Tutte 1963), paper §3.6 "Initialization": every interior vertex at the
// uniform (valence) average of its neighbours, the boundary loop on a circle, equally
// spaced by index as in the authors' code, the circle's area equal to the mesh area
// (radius sqrt(|M|/pi)). Bijective for a disk: the starting point of every method.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace uvpress::flatten {

// `boundary` in the direction of the triangles' boundary edges, so counter-clockwise
// triangles stay counter-clockwise. Returns u v per vertex. Solved with CHOLMOD on the
// interior Laplacian (SPD), in `order` (every vertex once: an elimination order found for
// another system on the mesh, solve::SparseSystem::vertex_order) when given - ordering a
// large mesh costs more than factorizing its Laplacian (camelhead-s3: 12 s of the set-up
// with CHOLMOD's own ordering) - else in CHOLMOD's.
std::vector<double> tutte_embedding(size_t vertex_count, const std::vector<uint32_t>& triangles,
                                    const std::vector<uint32_t>& boundary, double area,
                                    const std::vector<uint32_t>* order = nullptr);

}  // namespace uvpress::flatten
