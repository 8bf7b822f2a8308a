#include "flatten/disk_topology.h"

#include "flatten/flatten.h"

#include "core/disjoint_sets.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace uvpress::flatten {

namespace {

std::string plural(size_t n, const char* word) {
  return std::to_string(n) + " " + word + (n == 1 ? "" : "s");
}

}  // namespace

DiskTopology check_disk(const std::vector<uint32_t>& input_triangles, size_t vertex_count) {
  const size_t nt = input_triangles.size() / 3;
  if (nt == 0) throw FlattenError("no triangles");
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t* v = &input_triangles[3 * t];
    for (int k = 0; k < 3; ++k)
      if (v[k] >= vertex_count) throw FlattenError("triangle " + std::to_string(t) + " has a vertex out of range");
    if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0])
      throw FlattenError("not a disk: triangle " + std::to_string(t) + " repeats a vertex");
  }

  DiskTopology out;
  std::vector<uint32_t> compact(vertex_count, UINT32_MAX);
  for (uint32_t v : input_triangles) compact[v] = 0;
  for (size_t v = 0; v < vertex_count; ++v)
    if (compact[v] == 0) compact[v] = uint32_t(out.used_vertices.size()), out.used_vertices.push_back(uint32_t(v));
  out.triangles.resize(input_triangles.size());
  for (size_t i = 0; i < input_triangles.size(); ++i) out.triangles[i] = compact[input_triangles[i]];
  const size_t nv = out.used_vertices.size();
  const auto& tris = out.triangles;

  // Half-edges (from, to), sorted by undirected edge: a manifold, oriented mesh has each
  // undirected edge once (boundary) or twice in opposite directions (interior).
  struct HalfEdge {
    uint32_t lo, hi;  // undirected key
    uint32_t from, to;
  };
  std::vector<HalfEdge> he;
  he.reserve(3 * nt);
  for (size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      uint32_t a = tris[3 * t + size_t(k)], b = tris[3 * t + size_t((k + 1) % 3)];
      he.push_back({std::min(a, b), std::max(a, b), a, b});
    }
  std::sort(he.begin(), he.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.lo != y.lo ? x.lo < y.lo : x.hi != y.hi ? x.hi < y.hi : x.from < y.from;
  });
  size_t edges = 0, nonmanifold = 0, misoriented = 0;
  std::vector<uint32_t> boundary_next(nv, UINT32_MAX);  // boundary half-edge from -> to
  size_t nonmanifold_vertices = 0;
  std::vector<uint8_t> bad_vertex(nv, 0);
  for (size_t i = 0; i < he.size();) {
    size_t j = i;
    while (j < he.size() && he[j].lo == he[i].lo && he[j].hi == he[i].hi) ++j;
    ++edges;
    size_t count = j - i;
    if (count > 2) ++nonmanifold;
    else if (count == 2 && he[i].from == he[i + 1].from) ++misoriented;
    else if (count == 1) {
      uint32_t from = he[i].from;
      if (boundary_next[from] != UINT32_MAX) {
        if (!bad_vertex[from]) ++nonmanifold_vertices;
        bad_vertex[from] = 1;
      }
      boundary_next[from] = he[i].to;
    }
    i = j;
  }

  DisjointSets sets(nv);
  for (size_t t = 0; t < nt; ++t) sets.unite(tris[3 * t], tris[3 * t + 1]), sets.unite(tris[3 * t], tris[3 * t + 2]);
  size_t components = 0;
  for (size_t v = 0; v < nv; ++v) components += sets.find(uint32_t(v)) == v;

  size_t loops = 0;
  if (nonmanifold == 0 && misoriented == 0 && nonmanifold_vertices == 0) {
    std::vector<uint8_t> seen(nv, 0);
    for (size_t v = 0; v < nv; ++v) {
      if (boundary_next[v] == UINT32_MAX || seen[v]) continue;
      ++loops;
      std::vector<uint32_t> loop;
      for (uint32_t w = uint32_t(v); !seen[w]; w = boundary_next[w]) {
        seen[w] = 1;
        loop.push_back(w);
        if (boundary_next[w] == UINT32_MAX) break;  // cannot happen on a manifold mesh
      }
      if (loops == 1) out.boundary = std::move(loop);
    }
  }

  std::vector<std::string> why;
  if (nonmanifold) why.push_back(plural(nonmanifold, "non-manifold edge") + " (shared by more than 2 triangles)");
  if (misoriented) why.push_back(plural(misoriented, "edge") + " with inconsistently oriented triangles");
  if (nonmanifold_vertices) why.push_back(plural(nonmanifold_vertices, "non-manifold vertex") + " (boundaries touch)");
  if (components != 1) why.push_back(plural(components, "connected component"));
  if (why.empty()) {
    if (loops != 1) why.push_back(plural(loops, "boundary loop") + " (a disk has exactly 1)");
    // Euler characteristic V - E + F = 2 - 2g - b; a disk has g = 0, b = 1.
    long chi = long(nv) - long(edges) + long(nt);
    if (loops == 1 && chi != 1) why.push_back("genus " + std::to_string((1 - chi) / 2) + " (a disk has genus 0)");
  }
  if (!why.empty()) {
    std::string msg = "not a disk: ";
    for (size_t i = 0; i < why.size(); ++i) msg += (i ? ", " : "") + why[i];
    throw FlattenError(msg);
  }
  return out;
}

FilledHoles fill_holes(const std::vector<double>& positions, const std::vector<uint32_t>& triangles) {
  FilledHoles out{positions, triangles, 0};
  const size_t nv = positions.size() / 3, nt = triangles.size() / 3;
  // Directed half-edges; a boundary half-edge has no reverse twin.
  std::vector<std::pair<uint32_t, uint32_t>> he;
  he.reserve(3 * nt);
  for (size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = triangles[3 * t + size_t(k)], b = triangles[3 * t + size_t((k + 1) % 3)];
      if (a >= nv || b >= nv || a == b) return out;
      he.push_back({a, b});
    }
  std::sort(he.begin(), he.end());
  for (size_t i = 1; i < he.size(); ++i)
    if (he[i] == he[i - 1]) return out;  // inconsistent orientation or a non-manifold edge
  std::vector<uint32_t> next(nv, UINT32_MAX);
  for (const auto& [a, b] : he) {
    if (std::binary_search(he.begin(), he.end(), std::make_pair(b, a))) continue;
    if (next[a] != UINT32_MAX) return out;  // two boundary edges leave a: a non-manifold vertex
    next[a] = b;
  }
  // The loops, with their 3-D lengths.
  std::vector<std::vector<uint32_t>> loops;
  std::vector<double> length;
  std::vector<uint8_t> seen(nv, 0);
  for (size_t v = 0; v < nv; ++v) {
    if (next[v] == UINT32_MAX || seen[v]) continue;
    std::vector<uint32_t> loop;
    double len = 0;
    uint32_t w = uint32_t(v);
    while (!seen[w]) {
      seen[w] = 1;
      loop.push_back(w);
      const uint32_t n = next[w];
      if (n == UINT32_MAX) return out;  // an open boundary path: not a manifold boundary
      double d2 = 0;
      for (int k = 0; k < 3; ++k) d2 += std::pow(positions[3 * size_t(n) + size_t(k)] - positions[3 * size_t(w) + size_t(k)], 2);
      len += std::sqrt(d2);
      w = n;
    }
    if (w != v) return out;  // the walk closed somewhere else
    loops.push_back(std::move(loop));
    length.push_back(len);
  }
  if (loops.size() < 2) return out;
  const size_t keep = size_t(std::max_element(length.begin(), length.end()) - length.begin());
  for (size_t l = 0; l < loops.size(); ++l) {
    if (l == keep) continue;
    const auto& loop = loops[l];
    const uint32_t c = uint32_t(out.positions.size() / 3);
    double centroid[3] = {0, 0, 0};
    for (uint32_t v : loop)
      for (int k = 0; k < 3; ++k) centroid[k] += positions[3 * size_t(v) + size_t(k)] / double(loop.size());
    out.positions.insert(out.positions.end(), centroid, centroid + 3);
    // The boundary edge a -> b lies in a triangle (a, b, .): the fan takes it as b -> a.
    for (size_t i = 0; i < loop.size(); ++i) {
      const uint32_t a = loop[i], b = loop[(i + 1) % loop.size()];
      out.triangles.insert(out.triangles.end(), {b, a, c});
    }
    ++out.filled_loops;
  }
  return out;
}

}  // namespace uvpress::flatten
