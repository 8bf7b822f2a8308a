#include "atlas/charts.h"

#include "core/disjoint_sets.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numeric>
#include <unordered_map>

namespace uvpress::atlas {

Charts find_charts(const Mesh& mesh) {
  const size_t nt = mesh.triangle_count();
  DisjointSets sets(mesh.uv_count());
  for (size_t t = 0; t < nt; ++t) {
    sets.unite(mesh.uv_triangles[3 * t], mesh.uv_triangles[3 * t + 1]);
    sets.unite(mesh.uv_triangles[3 * t], mesh.uv_triangles[3 * t + 2]);
  }
  Charts charts;
  charts.chart_of_triangle.resize(nt);
  std::unordered_map<uint32_t, uint32_t> id;  // root -> chart number, in order of first triangle
  for (size_t t = 0; t < nt; ++t) {
    auto [it, fresh] = id.emplace(sets.find(mesh.uv_triangles[3 * t]), charts.count);
    if (fresh) ++charts.count;
    charts.chart_of_triangle[t] = it->second;
  }
  return charts;
}

std::vector<ChartMesh> split_charts(const Mesh& mesh, const Charts& charts) {
  std::vector<ChartMesh> out(charts.count);
  std::vector<uint32_t> local(mesh.uv_count(), UINT32_MAX);  // UV vertex -> index in its chart
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    ChartMesh& c = out[charts.chart_of_triangle[t]];
    c.triangles.push_back(uint32_t(t));
    for (size_t k = 0; k < 3; ++k) {
      const uint32_t u = mesh.uv_triangles[3 * t + k];
      if (local[u] == UINT32_MAX) local[u] = uint32_t(c.uv_vertices.size()), c.uv_vertices.push_back(u);
      c.corners.push_back(local[u]);
    }
  }
  return out;
}

Mesh chart_surface(const Mesh& mesh, const ChartMesh& chart) {
  Mesh m;
  m.positions.resize(3 * chart.uv_vertices.size());
  for (size_t i = 0; i < chart.triangles.size(); ++i)
    for (size_t k = 0; k < 3; ++k) {
      const uint32_t p = mesh.triangles[3 * size_t(chart.triangles[i]) + k];
      for (size_t d = 0; d < 3; ++d) m.positions[3 * size_t(chart.corners[3 * i + k]) + d] = mesh.positions[3 * size_t(p) + d];
    }
  m.triangles = chart.corners;
  return m;
}

Mesh weld_uv_mesh(const float* positions, const float* uvs, size_t vertex_count, const uint32_t* indices,
                  size_t index_count) {
  // Keys are the float bits; "+ 0.0f" folds -0 into +0 first.
  using Key = std::array<uint32_t, 5>;
  struct Hash {
    size_t operator()(const Key& k) const {
      size_t h = 0;
      for (uint32_t x : k) h = h * 0x9E3779B97F4A7C15ull + x;
      return h;
    }
  };
  Mesh m;
  std::unordered_map<Key, uint32_t, Hash> position_id, uv_id;  // position; position + UV
  std::vector<uint32_t> to_position(vertex_count), to_uv(vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) {
    float f[5] = {positions[3 * v] + 0.0f, positions[3 * v + 1] + 0.0f, positions[3 * v + 2] + 0.0f,
                  uvs[2 * v] + 0.0f, uvs[2 * v + 1] + 0.0f};
    Key key{}, key_p{};
    std::memcpy(key.data(), f, sizeof f);
    std::memcpy(key_p.data(), f, 3 * sizeof(float));
    auto [p, new_p] = position_id.emplace(key_p, uint32_t(position_id.size()));
    if (new_p) m.positions.insert(m.positions.end(), {f[0], f[1], f[2]});
    auto [u, new_u] = uv_id.emplace(key, uint32_t(uv_id.size()));
    if (new_u) m.uvs.insert(m.uvs.end(), {f[3], f[4]});
    to_position[v] = p->second, to_uv[v] = u->second;
  }
  const size_t n = index_count / 3 * 3;
  m.triangles.resize(n), m.uv_triangles.resize(n);
  for (size_t i = 0; i < n; ++i) m.triangles[i] = to_position[indices[i]], m.uv_triangles[i] = to_uv[indices[i]];
  return m;
}

std::array<double, 2> shelf_layout(std::vector<ShelfBox>& boxes, double gap) {
  double total = 0, widest = 0;
  for (const auto& b : boxes) total += b.w * b.h, widest = std::max(widest, b.w);
  std::vector<size_t> order(boxes.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return boxes[a].h > boxes[b].h; });
  const double width = std::max(widest, std::sqrt(total) * 1.1);
  double x = gap, y = gap, row = 0, used_w = 0;
  for (size_t i : order) {
    ShelfBox& b = boxes[i];
    if (x > gap && x + b.w > width) x = gap, y += row + gap, row = 0;
    b.x = x, b.y = y;
    x += b.w + gap, row = std::max(row, b.h), used_w = std::max(used_w, x);
  }
  return {used_w, y + row + gap};
}

std::array<double, 2> shelve_charts(std::vector<std::vector<double>*>& chart_uvs) {
  std::vector<ShelfBox> boxes(chart_uvs.size());
  std::vector<std::array<double, 2>> lo(chart_uvs.size());
  double total = 0;
  for (size_t c = 0; c < chart_uvs.size(); ++c) {
    double l[2] = {1e300, 1e300}, h[2] = {-1e300, -1e300};
    const std::vector<double>& uv = *chart_uvs[c];
    for (size_t i = 0; i < uv.size(); ++i) l[i % 2] = std::min(l[i % 2], uv[i]), h[i % 2] = std::max(h[i % 2], uv[i]);
    lo[c] = {l[0], l[1]};
    boxes[c].w = h[0] - l[0], boxes[c].h = h[1] - l[1];
    total += boxes[c].w * boxes[c].h;
  }
  const auto extent = shelf_layout(boxes, 0.01 * std::sqrt(total));
  for (size_t c = 0; c < chart_uvs.size(); ++c) {
    std::vector<double>& uv = *chart_uvs[c];
    const double at[2] = {boxes[c].x, boxes[c].y};
    for (size_t i = 0; i < uv.size(); ++i) uv[i] = uv[i] - lo[c][i % 2] + at[i % 2];
  }
  return extent;
}

}  // namespace uvpress::atlas
