#include "perceptual/triangle_view.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <unordered_map>

namespace uvpress::perceptual {

using Vec3 = Eigen::Vector3d;

namespace {

constexpr double kMaxNeighbourTexelsPerPixel = 8;  // see the ring loop in make_triangle_views
constexpr uint32_t kMaxPatchGrid = 16;

// Vertex id by position: glTF splits vertices at UV seams and normal creases, but the
// one-ring is about the surface, so neighbours are found through welded positions.
std::vector<uint32_t> weld_positions(const float* p, size_t n) {
  struct Hash {
    size_t operator()(const std::array<uint32_t, 3>& k) const { return (k[0] * 73856093u) ^ (k[1] * 19349663u) ^ (k[2] * 83492791u); }
  };
  std::unordered_map<std::array<uint32_t, 3>, uint32_t, Hash> ids;
  std::vector<uint32_t> out(n);
  for (size_t v = 0; v < n; ++v) {
    std::array<uint32_t, 3> key;
    for (int c = 0; c < 3; ++c) {
      float f = p[3 * v + size_t(c)] + 0.0f;
      std::memcpy(&key[size_t(c)], &f, 4);
    }
    out[v] = ids.emplace(key, uint32_t(ids.size())).first->second;
  }
  return out;
}

// Plane c0 + c1 x + c2 y through three (x, y, value) points; false when degenerate.
bool plane(const double x[3], const double y[3], const double v[3], float out[3]) {
  double det = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
  if (std::abs(det) < 1e-12) return false;
  double c1 = ((v[1] - v[0]) * (y[2] - y[0]) - (v[2] - v[0]) * (y[1] - y[0])) / det;
  double c2 = ((x[1] - x[0]) * (v[2] - v[0]) - (x[2] - x[0]) * (v[1] - v[0])) / det;
  double c0 = v[0] - c1 * x[0] - c2 * y[0];
  out[0] = float(c0), out[1] = float(c1), out[2] = float(c2);
  return true;
}

// Sutherland-Hodgman against |x|, |y| <= bound.
std::vector<std::array<double, 2>> clip(std::vector<std::array<double, 2>> poly, double bound) {
  for (int axis = 0; axis < 2; ++axis)
    for (double sign : {1.0, -1.0}) {
      std::vector<std::array<double, 2>> out;
      for (size_t i = 0; i < poly.size(); ++i) {
        auto a = poly[i], b = poly[(i + 1) % poly.size()];
        double da = bound - sign * a[size_t(axis)], db = bound - sign * b[size_t(axis)];
        if (da >= 0) out.push_back(a);
        if ((da >= 0) != (db >= 0)) {
          double t = da / (da - db);
          out.push_back({a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])});
        }
      }
      poly = std::move(out);
      if (poly.empty()) return poly;
    }
  return poly;
}

}  // namespace

TriangleViews make_triangle_views(const TriangleViewInput& in, uint32_t size, const std::vector<uint32_t>& which,
                                  uint32_t max_patches, double min_texels_per_pixel) {
  TriangleViews out;
  engine::ViewSetDesc& desc = out.desc;
  desc.size = size;
  const std::vector<uint32_t> welded = weld_positions(in.positions, in.vertex_count);
  // Triangles around each welded vertex.
  std::vector<std::vector<uint32_t>> around(in.vertex_count);
  for (uint32_t t = 0; t < in.triangle_count; ++t)
    for (int c = 0; c < 3; ++c) {
      auto& list = around[welded[in.indices[3 * t + uint32_t(c)]]];
      if (list.empty() || list.back() != t) list.push_back(t);
    }
  auto vertex = [&](uint32_t v) {
    return Vec3(in.positions[3 * v], in.positions[3 * v + 1], in.positions[3 * v + 2]);
  };
  const double W = in.texture_width, H = in.texture_height;
  auto texel_s = [&](uint32_t v) { return in.uvs[2 * v] * W - 0.5; };
  auto texel_t = [&](uint32_t v) { return in.uvs[2 * v + 1] * H - 0.5; };
  // Two corners are the same chart vertex when they weld in space and have equal UVs.
  auto same_chart_vertex = [&](uint32_t a, uint32_t b) {
    return welded[a] == welded[b] && in.uvs[2 * a] == in.uvs[2 * b] && in.uvs[2 * a + 1] == in.uvs[2 * b + 1];
  };
  const double bound = double(shader::kViewGuardBand) - 8.0;

  std::vector<uint32_t> all;
  const std::vector<uint32_t>* list = &which;
  if (which.empty()) {
    all.resize(in.triangle_count);
    for (uint32_t t = 0; t < in.triangle_count; ++t) all[t] = t;
    list = &all;
  }
  out.first_view.reserve(list->size() + 1);
  for (uint32_t tri : *list) {
    out.first_view.push_back(uint32_t(desc.views.size()));
    const uint32_t* f = &in.indices[3 * tri];
    Vec3 a = vertex(f[0]), b = vertex(f[1]), c = vertex(f[2]);
    // Appendix A, Algorithm 1.
    Vec3 C = (a + b + c) / 3.0, N = (b - a).cross(c - a);
    if (N.norm() < 1e-30 || (a - C).norm() < 1e-30) {  // degenerate: an empty view
      engine::ViewDesc view{uint32_t(desc.triangles.size()), 1, 1, 0};
      desc.triangles.push_back(shader::ViewTriangle{});
      desc.views.push_back(view);
      out.texels_per_pixel.push_back(0.0f);
      out.complete.push_back(1);
      continue;
    }
    N.normalize();
    Vec3 R = (a - C).normalized(), U = N.cross(R).normalized();
    double lo_x = INFINITY, hi_x = -INFINITY, lo_y = INFINITY, hi_y = -INFINITY;
    for (const Vec3& v : {a, b, c}) {
      double x = (v - C).dot(R), y = (v - C).dot(U);
      lo_x = std::min(lo_x, x), hi_x = std::max(hi_x, x), lo_y = std::min(lo_y, y), hi_y = std::max(hi_y, y);
    }
    double w = hi_x - lo_x, h = hi_y - lo_y;
    if (w > h) lo_y -= (w - h) / 2, hi_y += (w - h) / 2;
    else lo_x -= (h - w) / 2, hi_x += (h - w) / 2;
    double side = std::max(w, h);

    // Texels per unit length along the worst direction: the largest singular value of
    // d(s, t)/d(x, y) over the triangle's plane.
    double sigma = 0;
    {
      double x[3], y[3], s[3], t[3];
      for (int k = 0; k < 3; ++k) {
        Vec3 d = vertex(f[k]) - C;
        x[k] = d.dot(R), y[k] = d.dot(U), s[k] = texel_s(f[k]), t[k] = texel_t(f[k]);
      }
      const double det = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
      if (std::abs(det) > 0) {
        const double sx = ((s[1] - s[0]) * (y[2] - y[0]) - (s[2] - s[0]) * (y[1] - y[0])) / det;
        const double sy = ((x[1] - x[0]) * (s[2] - s[0]) - (x[2] - x[0]) * (s[1] - s[0])) / det;
        const double tx = ((t[1] - t[0]) * (y[2] - y[0]) - (t[2] - t[0]) * (y[1] - y[0])) / det;
        const double ty = ((x[1] - x[0]) * (t[2] - t[0]) - (x[2] - x[0]) * (t[1] - t[0])) / det;
        const double q = sx * sx + sy * sy + tx * tx + ty * ty, d2 = sx * ty - sy * tx;
        sigma = std::sqrt(std::max(0.0, 0.5 * (q + std::sqrt(std::max(0.0, q * q - 4 * d2 * d2)))));
      }
    }
    // Patches: n x n sub-squares so that each resolves its texels; keep those whose centre
    // lies in the triangle (the centroid's square when none does), then at most
    // `max_patches` of them, evenly spread.
    // (At most kMaxPatchGrid a side: slivers with a large UV extent are not worth more.)
    if (min_texels_per_pixel > 0 && sigma > 0 && side * sigma < min_texels_per_pixel * size) {
      // Too magnified: widen the square about its centre to min_texels_per_pixel.
      const double cx = lo_x + 0.5 * side, cy = hi_y - 0.5 * side;
      side = min_texels_per_pixel * size / sigma;
      lo_x = cx - 0.5 * side, hi_x = cx + 0.5 * side, lo_y = cy - 0.5 * side, hi_y = cy + 0.5 * side;
    }
    const double grid = std::ceil(side * sigma / double(size) - 1e-9);
    const uint32_t n = uint32_t(std::clamp(grid, 1.0, double(kMaxPatchGrid)));
    std::vector<std::array<uint32_t, 2>> patches;
    if (n == 1) {
      patches.push_back({0, 0});
    } else {
      double px[3], py[3];
      for (int k = 0; k < 3; ++k) {
        Vec3 d = vertex(f[k]) - C;
        px[k] = d.dot(R), py[k] = d.dot(U);
      }
      auto inside = [&](double x, double y) {
        double e[3];
        for (int k = 0; k < 3; ++k) {
          int l = (k + 1) % 3;
          e[k] = (px[l] - px[k]) * (y - py[k]) - (py[l] - py[k]) * (x - px[k]);
        }
        return (e[0] >= 0 && e[1] >= 0 && e[2] >= 0) || (e[0] <= 0 && e[1] <= 0 && e[2] <= 0);
      };
      for (uint32_t j = 0; j < n; ++j)
        for (uint32_t i = 0; i < n; ++i)
          if (inside(lo_x + (i + 0.5) * side / n, hi_y - (j + 0.5) * side / n)) patches.push_back({i, j});
      if (patches.empty())
        patches.push_back({std::min(n - 1, uint32_t((0 - lo_x) / side * n)), std::min(n - 1, uint32_t((hi_y - 0) / side * n))});
      const uint32_t m = uint32_t(patches.size());
      const uint32_t keep = std::min(m, std::max(1u, max_patches));
      std::vector<std::array<uint32_t, 2>> kept;
      for (uint32_t k = 0; k < keep; ++k) kept.push_back(patches[size_t((2 * uint64_t(k) + 1) * m / (2 * keep))]);
      out.complete.push_back(keep == m);
      patches = std::move(kept);
    }
    if (n == 1) out.complete.push_back(1);

    // The ring: this triangle first, then its neighbours by distance of their centroid.
    std::vector<uint32_t> ring = {tri};
    for (int k = 0; k < 3; ++k)
      for (uint32_t r : around[welded[f[k]]])
        if (std::find(ring.begin(), ring.end(), r) == ring.end()) ring.push_back(r);
    auto centroid_distance = [&](uint32_t t) {
      const uint32_t* g = &in.indices[3 * t];
      return ((vertex(g[0]) + vertex(g[1]) + vertex(g[2])) / 3.0 - C).squaredNorm();
    };
    std::stable_sort(ring.begin() + 1, ring.end(),
                     [&](uint32_t x, uint32_t y) { return centroid_distance(x) < centroid_distance(y); });
    // Charts among the ring: union of ring triangles that share a chart vertex.
    std::vector<uint32_t> parent(ring.size());
    for (size_t k = 0; k < ring.size(); ++k) parent[k] = uint32_t(k);
    auto find = [&](uint32_t k) {
      while (parent[k] != k) k = parent[k] = parent[parent[k]];
      return k;
    };
    for (size_t p = 0; p < ring.size(); ++p)
      for (size_t q = p + 1; q < ring.size(); ++q) {
        const uint32_t* g = &in.indices[3 * ring[p]];
        const uint32_t* h2 = &in.indices[3 * ring[q]];
        bool shared = false;
        for (int x = 0; x < 3 && !shared; ++x)
          for (int y = 0; y < 3 && !shared; ++y) shared = same_chart_vertex(g[x], h2[y]);
        if (shared) parent[find(uint32_t(q))] = find(uint32_t(p));
      }
    // Groups numbered by first appearance (the view's own chart is 0), each with its anchor.
    std::vector<uint32_t> group_of(ring.size());
    std::vector<uint32_t> root_of_group;
    std::vector<std::array<double, 2>> anchor;
    for (size_t k = 0; k < ring.size(); ++k) {
      const uint32_t root = find(uint32_t(k));
      auto it = std::find(root_of_group.begin(), root_of_group.end(), root);
      if (it != root_of_group.end()) {
        group_of[k] = std::min(uint32_t(it - root_of_group.begin()), shader::kViewMaxGroups - 1);
        continue;
      }
      group_of[k] = std::min(uint32_t(root_of_group.size()), shader::kViewMaxGroups - 1);
      root_of_group.push_back(root);
      const uint32_t* g = &in.indices[3 * ring[k]];
      if (k == 0) {
        anchor.push_back({0, 0});  // per view below (the view's centre)
        continue;
      }
      // The seam vertex: a corner welded to one of the view triangle's corners.
      uint32_t v = g[0];
      for (int x = 0; x < 3; ++x)
        for (int y = 0; y < 3; ++y)
          if (welded[g[x]] == welded[f[y]]) v = g[x];
      anchor.push_back({std::round(texel_s(v)), std::round(texel_t(v))});
    }
    const uint32_t group_count = std::min(uint32_t(root_of_group.size()), shader::kViewMaxGroups);

    const double sub = side / n;          // patch side, space units
    const double scale = size / sub;      // pixels per unit length
    for (const auto& patch : patches) {
      const double plo_x = lo_x + patch[0] * sub, phi_y = hi_y - patch[1] * sub;
      engine::ViewDesc view{uint32_t(desc.triangles.size()), 0, group_count, 0};
      out.texels_per_pixel.push_back(float(sigma / scale));
      // Group 0's anchor: the triangle's centroid (one view) or the patch's centre, in the
      // view triangle's texel coordinates.
      double anchor0[2];
      {
        const double cx = n == 1 ? 0.0 : plo_x + sub / 2, cy = n == 1 ? 0.0 : phi_y - sub / 2;
        double x[3], y[3], s[3], t[3];
        for (int k = 0; k < 3; ++k) {
          Vec3 d = vertex(f[k]) - C;
          x[k] = d.dot(R), y[k] = d.dot(U), s[k] = texel_s(f[k]), t[k] = texel_t(f[k]);
        }
        const double det = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
        const double l1 = ((cx - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (cy - y[0])) / det;
        const double l2 = ((x[1] - x[0]) * (cy - y[0]) - (cx - x[0]) * (y[1] - y[0])) / det;
        anchor0[0] = std::round(s[0] + l1 * (s[1] - s[0]) + l2 * (s[2] - s[0]));
        anchor0[1] = std::round(t[0] + l1 * (t[1] - t[0]) + l2 * (t[2] - t[0]));
      }
      for (size_t r = 0; r < ring.size(); ++r) {
        const uint32_t* g = &in.indices[3 * ring[r]];
        double x[3], y[3], z[3], s[3], tt[3];
        for (int k = 0; k < 3; ++k) {
          Vec3 d = vertex(g[k]) - C;
          x[k] = (d.dot(R) - plo_x) * scale;
          y[k] = (phi_y - d.dot(U)) * scale;  // pixel rows go down, U goes up
          z[k] = d.dot(N);                     // towards the eye at C + 500 N: larger is nearer
          s[k] = texel_s(g[k]);
          tt[k] = texel_t(g[k]);
        }
        shader::ViewTriangle vt{};
        if (!plane(x, y, z, vt.depth) || !plane(x, y, s, vt.s) || !plane(x, y, tt, vt.t)) continue;  // edge-on
        // A neighbour nearly edge-on to this camera (a fold) maps a sliver of pixels to a
        // long run of texels: it would only blow up the candidate tile. Left out of the view
        // (background in both renders), like the view's own triangle past the engine's bound.
        const double grad = std::max({std::abs(vt.s[1]), std::abs(vt.s[2]), std::abs(vt.t[1]), std::abs(vt.t[2])});
        if (grad > (r == 0 ? double(shader::kViewMaxTexelsPerPixel) : kMaxNeighbourTexelsPerPixel)) continue;
        vt.group = group_of[r];
        const double* an = group_of[r] == 0 ? anchor0 : anchor[group_of[r]].data();
        vt.anchor_s = float(an[0]), vt.anchor_t = float(an[1]);
        std::vector<std::array<double, 2>> poly = {{x[0], y[0]}, {x[1], y[1]}, {x[2], y[2]}};
        bool in_band = true;
        for (auto& p : poly) in_band &= std::abs(p[0]) <= bound && std::abs(p[1]) <= bound;
        if (!in_band) poly = clip(poly, bound);
        for (size_t k = 1; k + 1 < poly.size(); ++k) {
          if (view.triangle_count == shader::kViewMaxTriangles) break;
          const std::array<double, 2>* p3[3] = {&poly[0], &poly[k], &poly[k + 1]};
          for (int q = 0; q < 3; ++q) vt.xy[2 * q] = float((*p3[q])[0]), vt.xy[2 * q + 1] = float((*p3[q])[1]);
          desc.triangles.push_back(vt);
          ++view.triangle_count;
        }
      }
      if (view.triangle_count == 0) {  // keep the range valid: an empty placeholder triangle
        desc.triangles.push_back(shader::ViewTriangle{});
        view.triangle_count = 1;
      }
      desc.views.push_back(view);
    }
  }
  out.first_view.push_back(uint32_t(desc.views.size()));
  return out;
}

}  // namespace uvpress::perceptual
