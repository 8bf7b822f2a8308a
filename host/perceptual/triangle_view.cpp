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

std::vector<float> luminance_plane(const Image& img) {
  std::vector<float> y(size_t(img.width) * img.height);
  for (size_t i = 0; i < y.size(); ++i) {
    const float* px = &img.pixels[i * img.channels];
    y[i] = img.channels >= 3 ? 0.299f * px[0] + 0.587f * px[1] + 0.114f * px[2] : px[0];
  }
  return y;
}

namespace {

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

engine::ViewSetDesc make_triangle_views(const TriangleViewInput& in, uint32_t size, const std::vector<uint32_t>& which) {
  engine::ViewSetDesc desc;
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
  const double bound = double(shader::kViewGuardBand) - 8.0;

  std::vector<uint32_t> all;
  const std::vector<uint32_t>* list = &which;
  if (which.empty()) {
    all.resize(in.triangle_count);
    for (uint32_t t = 0; t < in.triangle_count; ++t) all[t] = t;
    list = &all;
  }
  for (uint32_t tri : *list) {
    const uint32_t* f = &in.indices[3 * tri];
    Vec3 a = vertex(f[0]), b = vertex(f[1]), c = vertex(f[2]);
    // Appendix A, Algorithm 1.
    Vec3 C = (a + b + c) / 3.0, N = (b - a).cross(c - a);
    engine::ViewDesc view{uint32_t(desc.triangles.size()), 0, 0, 0};
    double s_c = 0, t_c = 0;
    for (int k = 0; k < 3; ++k) s_c += in.uvs[2 * f[k]] * W - 0.5, t_c += in.uvs[2 * f[k] + 1] * H - 0.5;
    view.center_s = float(std::round(s_c / 3)), view.center_t = float(std::round(t_c / 3));
    if (N.norm() < 1e-30 || (a - C).norm() < 1e-30) {  // degenerate: an empty view
      desc.views.push_back(view);
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
    const double scale = size / std::max(w, h);  // pixels per unit length

    // The ring: this triangle first, then its neighbours by distance of their centroid.
    std::vector<uint32_t> ring = {tri};
    for (int k = 0; k < 3; ++k)
      for (uint32_t n : around[welded[f[k]]])
        if (std::find(ring.begin(), ring.end(), n) == ring.end()) ring.push_back(n);
    auto centroid_distance = [&](uint32_t t) {
      const uint32_t* g = &in.indices[3 * t];
      return ((vertex(g[0]) + vertex(g[1]) + vertex(g[2])) / 3.0 - C).squaredNorm();
    };
    std::stable_sort(ring.begin() + 1, ring.end(),
                     [&](uint32_t x, uint32_t y) { return centroid_distance(x) < centroid_distance(y); });

    for (uint32_t t : ring) {
      const uint32_t* g = &in.indices[3 * t];
      double x[3], y[3], z[3], s[3], tt[3];
      for (int k = 0; k < 3; ++k) {
        Vec3 d = vertex(g[k]) - C;
        x[k] = (d.dot(R) - lo_x) * scale;
        y[k] = (hi_y - d.dot(U)) * scale;  // pixel rows go down, U goes up
        z[k] = d.dot(N);                    // towards the eye at C + 500 N: larger is nearer
        s[k] = in.uvs[2 * g[k]] * W - 0.5;
        tt[k] = in.uvs[2 * g[k] + 1] * H - 0.5;
      }
      shader::ViewTriangle vt{};
      if (!plane(x, y, z, vt.depth) || !plane(x, y, s, vt.s) || !plane(x, y, tt, vt.t)) continue;  // edge-on
      std::vector<std::array<double, 2>> poly = {{x[0], y[0]}, {x[1], y[1]}, {x[2], y[2]}};
      bool inside = true;
      for (auto& p : poly) inside &= std::abs(p[0]) <= bound && std::abs(p[1]) <= bound;
      if (!inside) poly = clip(poly, bound);
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
  return desc;
}

}  // namespace uvpress::perceptual
