// Triangle set-up and binning of whole-mesh views (see mesh_render.h), shared by backends.
#include "mesh_render.h"

#include "backend.h"
#include "cpu/gmsd.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

namespace uvpress::engine {

void check_mesh_render(const MeshRenderDesc& d) {
  if (d.width < 8 || d.height < 8 || d.width > mesh::kMaxSide || d.height > mesh::kMaxSide)
    throw EngineError("render_mesh: image sides must be 8..1024 pixels");
  if (d.channels < 1 || d.channels > 4) throw EngineError("render_mesh: 1..4 channels");
  if (d.view_tiles_x < 1 || d.view_tiles_y < 1 || d.cameras.size() % (size_t(d.view_tiles_x) * d.view_tiles_y) != 0)
    throw EngineError("render_mesh: the cameras must be whole views of view_tiles_x x view_tiles_y tiles");
  if (!d.texture || d.texture_width == 0 || d.texture_height == 0) throw EngineError("render_mesh: no texture");
  if (d.mip_levels < 1 || d.mip_levels > mip_chain_levels(d.texture_width, d.texture_height))
    throw EngineError("render_mesh: mip levels must be 1.." + std::to_string(mip_chain_levels(d.texture_width, d.texture_height)));
  if (d.triangle_count && (!d.positions || !d.indices || !d.uvs)) throw EngineError("render_mesh: no mesh arrays");
  if (d.triangle_count >= kNoMeshTriangle) throw EngineError("render_mesh: too many triangles");
  for (size_t k = 0; k < 3 * d.triangle_count; ++k)
    if (d.indices[k] >= d.vertex_count) throw EngineError("render_mesh: index out of range");
  if (d.halve && (d.channels != 1 || d.coverage))
    throw EngineError("render_mesh: halved renders have one channel and no coverage");
  if (d.halve && ((d.view_tiles_x > 1 && d.width % 2) || (d.view_tiles_y > 1 && d.height % 2)))
    throw EngineError("render_mesh: halved views of several tiles need even tile sides");
}

std::array<uint32_t, 2> view_size(const MeshRenderDesc& d) {
  const uint32_t w = d.view_tiles_x * d.width, h = d.view_tiles_y * d.height;
  return d.halve ? std::array<uint32_t, 2>{(w + 1) / 2, (h + 1) / 2} : std::array<uint32_t, 2>{w, h};
}

void halve_renders(const MeshRenderDesc& d, const MeshRenders& full, MeshRenders& out) {
  const uint32_t W = d.view_tiles_x * d.width, H = d.view_tiles_y * d.height;  // a whole view
  const auto [w, h] = view_size(d);
  const size_t views = d.cameras.size() / (size_t(d.view_tiles_x) * d.view_tiles_y), k_count = full.textures;
  out.width = full.width, out.height = full.height, out.count = full.count, out.channels = 1, out.textures = full.textures;
  out.coverage.clear();
  out.pixels.resize(k_count * views * size_t(w) * h);
  for (size_t i = 0; i < k_count * views; ++i)
    cpu::gmsd_downsample(full.pixels.data() + i * size_t(W) * H, W, H, out.pixels.data() + i * size_t(w) * h);
}

uint32_t mip_chain_levels(uint32_t width, uint32_t height) {
  uint32_t levels = 1;
  for (uint32_t side = std::max(width, height); side > 1; side >>= 1) ++levels;
  return levels;
}

size_t mip_chain_texels(uint32_t width, uint32_t height, uint32_t levels) {
  size_t n = 0;
  for (uint32_t l = 0; l < levels; ++l) n += size_t(std::max(1u, width >> l)) * std::max(1u, height >> l);
  return n;
}

namespace mesh {

ImagePlace image_place(const MeshRenderDesc& d, uint32_t c) {
  const uint32_t per_view = d.view_tiles_x * d.view_tiles_y, t = c % per_view;
  const auto [w, h] = view_size(d);
  // A tile's offset in its view, halved with the view (tile sides are even then).
  const uint32_t tw = d.halve ? d.width / 2 : d.width, th = d.halve ? d.height / 2 : d.height;
  ImagePlace p;
  p.row_stride = w;
  p.origin = size_t(c / per_view) * w * h + size_t(t / d.view_tiles_x) * th * p.row_stride + size_t(t % d.view_tiles_x) * tw;
  return p;
}

uint32_t tiles_x(const MeshRenderDesc& d) { return (d.width + shader::kMeshTile - 1) / shader::kMeshTile; }
uint32_t tiles_y(const MeshRenderDesc& d) { return (d.height + shader::kMeshTile - 1) / shader::kMeshTile; }

namespace {

int64_t edge64(int64_t ax, int64_t ay, int64_t bx, int64_t by, int64_t px, int64_t py) {
  return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

// The convex polygon `poly` clipped to the rectangle [lo_x, hi_x] x [lo_y, hi_y]
// (Sutherland-Hodgman, one side at a time).
std::vector<std::array<double, 2>> clip_to_rect(std::vector<std::array<double, 2>> poly, double lo_x, double hi_x,
                                                double lo_y, double hi_y) {
  for (int side = 0; side < 4 && !poly.empty(); ++side) {
    const int axis = side / 2;
    const double bound = side == 0 ? lo_x : side == 1 ? hi_x : side == 2 ? lo_y : hi_y;
    auto inside = [&](const std::array<double, 2>& p) { return side % 2 == 0 ? p[axis] >= bound : p[axis] <= bound; };
    std::vector<std::array<double, 2>> out;
    for (size_t k = 0; k < poly.size(); ++k) {
      const auto& a = poly[k];
      const auto& b = poly[(k + 1) % poly.size()];
      if (inside(a)) out.push_back(a);
      if (inside(a) != inside(b)) {
        const double t = (bound - a[axis]) / (b[axis] - a[axis]);
        std::array<double, 2> c = {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])};
        c[axis] = bound;
        out.push_back(c);
      }
    }
    poly = std::move(out);
  }
  return poly;
}

}  // namespace

ViewSetup setup_view(const MeshRenderDesc& d, uint32_t view) {
  ViewSetup out;
  const auto& m = d.cameras.at(view);
  const uint32_t tx = tiles_x(d), ty = tiles_y(d);
  std::vector<std::vector<uint32_t>> bins(size_t(tx) * ty);
  const double lo_x = -kGuardBand, hi_x = double(d.width) + kGuardBand;
  const double lo_y = -kGuardBand, hi_y = double(d.height) + kGuardBand;
  // Keeps a set-up triangle whose pixel box meets the image, binned by tile.
  auto bin = [&](const MeshTriangle& r) {
    // Pixel range: centres (16 i + 8) within the snapped box.
    const int32_t bx0 = std::min({r.x0, r.x1, r.x2}), bx1 = std::max({r.x0, r.x1, r.x2});
    const int32_t by0 = std::min({r.y0, r.y1, r.y2}), by1 = std::max({r.y0, r.y1, r.y2});
    const int32_t i_lo = std::max(0, (bx0 - 8 + 15) >> 4), i_hi = std::min(int32_t(d.width) - 1, (bx1 - 8) >> 4);
    const int32_t j_lo = std::max(0, (by0 - 8 + 15) >> 4), j_hi = std::min(int32_t(d.height) - 1, (by1 - 8) >> 4);
    if (i_lo > i_hi || j_lo > j_hi) return;
    const uint32_t id = uint32_t(out.triangles.size());
    out.triangles.push_back(r);
    const int32_t ts = int32_t(shader::kMeshTile);
    for (int32_t b = j_lo / ts; b <= j_hi / ts; ++b)
      for (int32_t a = i_lo / ts; a <= i_hi / ts; ++a) bins[size_t(b) * tx + size_t(a)].push_back(id);
  };
  // Snapped, positively oriented vertices; false for a degenerate triangle.
  auto snap = [](const double X[3], const double Y[3], MeshTriangle& r, int o[3]) {
    int32_t x[3], y[3];
    for (int k = 0; k < 3; ++k) x[k] = int32_t(std::floor(X[k] * 16.0 + 0.5)), y[k] = int32_t(std::floor(Y[k] * 16.0 + 0.5));
    const int64_t area = edge64(x[0], y[0], x[1], y[1], x[2], y[2]);
    if (area == 0) return false;
    o[0] = 0, o[1] = 1, o[2] = 2;
    if (area < 0) std::swap(o[1], o[2]);
    r.x0 = x[o[0]], r.y0 = y[o[0]], r.x1 = x[o[1]], r.y1 = y[o[1]], r.x2 = x[o[2]], r.y2 = y[o[2]];
    return true;
  };
  for (size_t t = 0; t < d.triangle_count; ++t) {
    double X[3], Y[3], W[3], S[3], T[3];
    bool keep = true, inside = true;
    for (int k = 0; k < 3; ++k) {
      const float* p = d.positions + 3 * size_t(d.indices[3 * t + size_t(k)]);
      const float* uv = d.uvs + 2 * size_t(d.indices[3 * t + size_t(k)]);
      double c[4];
      for (int r = 0; r < 4; ++r)
        c[r] = double(m[size_t(4 * r)]) * p[0] + double(m[size_t(4 * r + 1)]) * p[1] +
               double(m[size_t(4 * r + 2)]) * p[2] + double(m[size_t(4 * r + 3)]);
      if (!(c[3] > kNearW)) {
        keep = false;
        break;
      }
      X[k] = (c[0] / c[3] * 0.5 + 0.5) * d.width;
      Y[k] = (0.5 - 0.5 * c[1] / c[3]) * d.height;
      if (!(X[k] >= lo_x && X[k] <= hi_x && Y[k] >= lo_y && Y[k] <= hi_y)) inside = false;
      W[k] = 1.0 / c[3];
      S[k] = double(uv[0]) * d.texture_width - 0.5;
      T[k] = double(uv[1]) * d.texture_height - 0.5;
    }
    if (!keep || !std::isfinite(X[0] + X[1] + X[2] + Y[0] + Y[1] + Y[2])) continue;
    double SW[3], TW[3];
    for (int k = 0; k < 3; ++k) SW[k] = S[k] * W[k], TW[k] = T[k] * W[k];
    MeshTriangle r{};
    r.index = uint32_t(t);
    if (inside) {
      int o[3];
      if (!snap(X, Y, r, o)) continue;
      // Planes relative to vertex 0 over the snapped positions, solved in double.
      const double dx1 = (r.x1 - r.x0) / 16.0, dy1 = (r.y1 - r.y0) / 16.0;
      const double dx2 = (r.x2 - r.x0) / 16.0, dy2 = (r.y2 - r.y0) / 16.0;
      const double det = dx1 * dy2 - dx2 * dy1;
      auto plane = [&](const double f[3], float out[3]) {
        const double f0 = f[o[0]], f1 = f[o[1]] - f0, f2 = f[o[2]] - f0;
        out[0] = float(f0);
        out[1] = float((f1 * dy2 - f2 * dy1) / det);
        out[2] = float((dx1 * f2 - dx2 * f1) / det);
      };
      plane(W, r.inv_w);
      plane(SW, r.s_w);
      plane(TW, r.t_w);
      bin(r);
      continue;
    }
    // A triangle past the guard band (a tile of a larger view: eval's tiled renders) is
    // clipped to it and drawn as a fan. Its planes stay the whole triangle's, solved over
    // the unsnapped vertices (attributes over w are affine in screen space, so clipping in
    // the screen plane leaves them unchanged) and re-expressed at each piece's vertex 0.
    const double dx1 = X[1] - X[0], dy1 = Y[1] - Y[0], dx2 = X[2] - X[0], dy2 = Y[2] - Y[0];
    const double det = dx1 * dy2 - dx2 * dy1;
    if (!(std::abs(det) > 0)) continue;
    std::array<double, 3> planes[3];  // value at vertex 0 of the triangle, d/dx, d/dy
    const double* fs[3] = {W, SW, TW};
    for (int a = 0; a < 3; ++a) {
      const double f0 = fs[a][0], f1 = fs[a][1] - f0, f2 = fs[a][2] - f0;
      planes[a] = {f0, (f1 * dy2 - f2 * dy1) / det, (dx1 * f2 - dx2 * f1) / det};
    }
    const auto poly = clip_to_rect({{X[0], Y[0]}, {X[1], Y[1]}, {X[2], Y[2]}}, lo_x, hi_x, lo_y, hi_y);
    for (size_t k = 1; k + 1 < poly.size(); ++k) {
      const double PX[3] = {poly[0][0], poly[k][0], poly[k + 1][0]}, PY[3] = {poly[0][1], poly[k][1], poly[k + 1][1]};
      int o[3];
      if (!snap(PX, PY, r, o)) continue;
      float* outs[3] = {r.inv_w, r.s_w, r.t_w};
      for (int a = 0; a < 3; ++a) {
        outs[a][0] = float(planes[a][0] + planes[a][1] * (r.x0 / 16.0 - X[0]) + planes[a][2] * (r.y0 / 16.0 - Y[0]));
        outs[a][1] = float(planes[a][1]);
        outs[a][2] = float(planes[a][2]);
      }
      bin(r);
    }
  }
  out.bin_offsets.resize(bins.size() + 1);
  size_t total = 0;
  for (size_t b = 0; b < bins.size(); ++b) out.bin_offsets[b] = uint32_t(total), total += bins[b].size();
  out.bin_offsets.back() = uint32_t(total);
  out.bin_items.reserve(total);
  for (const auto& b : bins) out.bin_items.insert(out.bin_items.end(), b.begin(), b.end());
  return out;
}

}  // namespace mesh
}  // namespace uvpress::engine
