#include "flatten/tutte.h"

#include "flatten/flatten.h"
#include "solve/sparse_system.h"

#include <Eigen/CholmodSupport>
#include <Eigen/Sparse>

#include <algorithm>
#include <cmath>

namespace uvpress::flatten {

std::vector<double> tutte_embedding(size_t nv, const std::vector<uint32_t>& tris, const std::vector<uint32_t>& boundary,
                                    double area, const std::vector<uint32_t>* order) {
  constexpr double kPi = 3.14159265358979323846;
  const double radius = std::sqrt(area / kPi);
  std::vector<double> uv(2 * nv, 0.0);
  std::vector<int> interior_index(nv, -1);
  std::vector<uint8_t> on_boundary(nv, 0);
  for (size_t k = 0; k < boundary.size(); ++k) {
    const double a = 2 * kPi * double(k) / double(boundary.size());
    uv[2 * size_t(boundary[k])] = radius * std::cos(a);
    uv[2 * size_t(boundary[k]) + 1] = radius * std::sin(a);
    on_boundary[boundary[k]] = 1;
  }
  int ni = 0;
  if (order && order->size() == nv) {  // interior vertices numbered in the given order
    for (uint32_t v : *order)
      if (!on_boundary[v] && interior_index[v] < 0) interior_index[v] = ni++;
  }
  if (ni != int(nv) - int(boundary.size()) || !order) {  // no usable order: natural numbering
    ni = 0;
    std::fill(interior_index.begin(), interior_index.end(), -1);
    for (size_t v = 0; v < nv; ++v)
      if (!on_boundary[v]) interior_index[v] = ni++;
    order = nullptr;
  }
  if (ni == 0) return uv;

  // Uniform-weight Laplacian over undirected edges (each interior edge is seen from two
  // triangles; keep it once by taking the half-edge with from < to, or the boundary one).
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  edges.reserve(tris.size());
  for (size_t t = 0; t < tris.size() / 3; ++t)
    for (int k = 0; k < 3; ++k) {
      uint32_t a = tris[3 * t + size_t(k)], b = tris[3 * t + size_t((k + 1) % 3)];
      edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());

  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(ni, 2);
  std::vector<double> degree(nv, 0);
  for (auto [a, b] : edges) {
    degree[a] += 1, degree[b] += 1;
    const int ia = interior_index[a], ib = interior_index[b];
    if (ia >= 0 && ib >= 0) {
      triplets.emplace_back(std::max(ia, ib), std::min(ia, ib), -1.0);  // lower triangle
    } else if (ia >= 0) {
      rhs(ia, 0) += uv[2 * size_t(b)], rhs(ia, 1) += uv[2 * size_t(b) + 1];
    } else if (ib >= 0) {
      rhs(ib, 0) += uv[2 * size_t(a)], rhs(ib, 1) += uv[2 * size_t(a) + 1];
    }
  }
  for (size_t v = 0; v < nv; ++v)
    if (interior_index[v] >= 0) triplets.emplace_back(interior_index[v], interior_index[v], degree[v]);
  Eigen::SparseMatrix<double> L(ni, ni);
  L.setFromTriplets(triplets.begin(), triplets.end());
  solve::configure_blas_threads();
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> solver;
  if (order) {  // already numbered in elimination order
    solver.cholmod().nmethods = 1;
    solver.cholmod().method[0].ordering = CHOLMOD_NATURAL;
  }
  const solve::SerialCholmod serial;
  solver.compute(L);
  if (solver.info() != Eigen::Success) throw FlattenError("Tutte embedding: the Laplacian could not be factorized");
  Eigen::MatrixXd x = solver.solve(rhs);
  for (size_t v = 0; v < nv; ++v)
    if (interior_index[v] >= 0) uv[2 * v] = x(interior_index[v], 0), uv[2 * v + 1] = x(interior_index[v], 1);
  return uv;
}

}  // namespace uvpress::flatten
