// Whole-mesh renders on the CPU: the reference for render_mesh.comp (same integer
// rasterization, same fp32 operations in the same order per pixel) and the Engine default.
#include "mesh_render.h"

#include "backend.h"
#include "parallel_for.h"

#include <algorithm>
#include <cmath>
#include <thread>

namespace uvpress::engine {
namespace mesh {

namespace {

int32_t edge(int32_t ax, int32_t ay, int32_t bx, int32_t by, int32_t px, int32_t py) {
  return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

bool owns_edge(int32_t ax, int32_t ay, int32_t bx, int32_t by) {
  const int32_t dx = bx - ax, dy = by - ay;
  return dy > 0 || (dy == 0 && dx < 0);
}

float plane(const float c[3], float fx, float fy) {
  float v = c[0] + c[1] * fx;
  v += c[2] * fy;
  return v;
}

int32_t wrap(int32_t i, int32_t n) {
  const int32_t r = i % n;
  return r < 0 ? r + n : r;
}

// Adds weight x the bilinear sample of mip level `level` at level-0 texel coordinates
// (s, t) to out (first: out = instead of +=).
void sample_level(const MeshRenderDesc& d, uint32_t level, float s, float t, float weight, float* out, bool first) {
  const uint32_t C = d.channels;
  const int32_t TW = int32_t(std::max(1u, d.texture_width >> level)), TH = int32_t(std::max(1u, d.texture_height >> level));
  const float* tex = d.texture + mip_chain_texels(d.texture_width, d.texture_height, level) * C;
  if (level > 0) {
    // Texel centres of level l: s_l + 0.5 = (s + 0.5) W_l / W.
    s = (s + 0.5f) * (float(TW) / float(d.texture_width)) - 0.5f;
    t = (t + 0.5f) * (float(TH) / float(d.texture_height)) - 0.5f;
  }
  int32_t i0, j0, i1, j1;
  float fs, ft;
  if (d.repeat) {
    s = std::min(std::max(s, -16777216.0f), 16777216.0f);
    t = std::min(std::max(t, -16777216.0f), 16777216.0f);
    const float fs0 = std::floor(s), ft0 = std::floor(t);
    fs = s - fs0, ft = t - ft0;
    i0 = wrap(int32_t(fs0), TW), j0 = wrap(int32_t(ft0), TH);
    i1 = wrap(i0 + 1, TW), j1 = wrap(j0 + 1, TH);
  } else {
    s = std::min(std::max(s, 0.0f), float(TW - 1));
    t = std::min(std::max(t, 0.0f), float(TH - 1));
    const float fs0 = std::floor(s), ft0 = std::floor(t);
    fs = s - fs0, ft = t - ft0;
    i0 = int32_t(fs0), j0 = int32_t(ft0);
    i1 = std::min(i0 + 1, TW - 1), j1 = std::min(j0 + 1, TH - 1);
  }
  const float* t00 = tex + (size_t(j0) * size_t(TW) + size_t(i0)) * C;
  const float* t10 = tex + (size_t(j0) * size_t(TW) + size_t(i1)) * C;
  const float* t01 = tex + (size_t(j1) * size_t(TW) + size_t(i0)) * C;
  const float* t11 = tex + (size_t(j1) * size_t(TW) + size_t(i1)) * C;
  for (uint32_t c = 0; c < C; ++c) {
    float top = (1.0f - fs) * t00[c];
    top += fs * t10[c];
    float bottom = (1.0f - fs) * t01[c];
    bottom += fs * t11[c];
    float v = (1.0f - ft) * top;
    v += ft * bottom;
    if (first)
      out[c] = weight == 1.0f ? v : weight * v;
    else
      out[c] += weight * v;
  }
}

}  // namespace

void shade_tile(const MeshRenderDesc& d, const ViewSetup& setup, uint32_t tx, uint32_t ty, uint32_t* coverage,
                float* pixels) {
  const uint32_t bin = ty * tiles_x(d) + tx;
  const uint32_t first = setup.bin_offsets[bin], last = setup.bin_offsets[bin + 1];
  const uint32_t C = d.channels;
  const uint32_t i0 = tx * shader::kMeshTile, i1 = std::min(d.width, (tx + 1) * shader::kMeshTile);
  const uint32_t j0 = ty * shader::kMeshTile, j1 = std::min(d.height, (ty + 1) * shader::kMeshTile);
  // Visibility triangle by triangle over the pixels of its snapped box only (the kernel
  // walks the list pixel by pixel; the same updates in the same order per pixel, so the
  // same winner): most triangles of a detailed mesh cover a few pixels of the tile.
  constexpr uint32_t T = shader::kMeshTile;
  uint32_t best_of[T * T];
  float best_z_of[T * T];
  std::fill(best_of, best_of + T * T, kNoMeshTriangle);
  for (uint32_t k = first; k < last; ++k) {
    const MeshTriangle& r = setup.triangles[setup.bin_items[k]];
    // Pixel centres (16 i + 8) inside the box, clamped to the tile.
    const int32_t bx0 = std::min({r.x0, r.x1, r.x2}), bx1 = std::max({r.x0, r.x1, r.x2});
    const int32_t by0 = std::min({r.y0, r.y1, r.y2}), by1 = std::max({r.y0, r.y1, r.y2});
    const int32_t lo_i = std::max(int32_t(i0), (bx0 - 8 + 15) >> 4), hi_i = std::min(int32_t(i1) - 1, (bx1 - 8) >> 4);
    const int32_t lo_j = std::max(int32_t(j0), (by0 - 8 + 15) >> 4), hi_j = std::min(int32_t(j1) - 1, (by1 - 8) >> 4);
    for (int32_t j = lo_j; j <= hi_j; ++j)
      for (int32_t i = lo_i; i <= hi_i; ++i) {
        const int32_t px = 16 * i + 8, py = 16 * j + 8;
        const int32_t e0 = edge(r.x1, r.y1, r.x2, r.y2, px, py), e1 = edge(r.x2, r.y2, r.x0, r.y0, px, py),
                      e2 = edge(r.x0, r.y0, r.x1, r.y1, px, py);
        if (e0 < 0 || e1 < 0 || e2 < 0) continue;
        if ((e0 == 0 && !owns_edge(r.x1, r.y1, r.x2, r.y2)) || (e1 == 0 && !owns_edge(r.x2, r.y2, r.x0, r.y0)) ||
            (e2 == 0 && !owns_edge(r.x0, r.y0, r.x1, r.y1)))
          continue;
        const float cx = float(i) + 0.5f, cy = float(j) + 0.5f;
        const float fx = cx - float(r.x0) * 0.0625f, fy = cy - float(r.y0) * 0.0625f;
        const float z = plane(r.inv_w, fx, fy);
        const size_t t = size_t(j - int32_t(j0)) * T + size_t(i - int32_t(i0));
        if (best_of[t] == kNoMeshTriangle || z > best_z_of[t]) best_of[t] = setup.bin_items[k], best_z_of[t] = z;
      }
  }
  for (uint32_t j = j0; j < j1; ++j)
    for (uint32_t i = i0; i < i1; ++i) {
      const float cx = float(i) + 0.5f, cy = float(j) + 0.5f;
      const uint32_t best = best_of[(j - j0) * T + (i - i0)];
      const size_t p = size_t(j) * d.width + i;
      float* out = pixels + p * C;
      if (best == kNoMeshTriangle) {
        coverage[p] = kNoMeshTriangle;
        for (uint32_t c = 0; c < C; ++c) out[c] = 0.0f;
        continue;
      }
      const MeshTriangle& r = setup.triangles[best];
      coverage[p] = r.index;
      const float fx = cx - float(r.x0) * 0.0625f, fy = cy - float(r.y0) * 0.0625f;
      const float iw = plane(r.inv_w, fx, fy);
      const float s = plane(r.s_w, fx, fy) / iw;
      const float t = plane(r.t_w, fx, fy) / iw;
      float lod = 0.0f;
      if (d.mip_levels > 1) {
        // d(s, t)/d(x, y) of s = S / Iw with S, Iw affine: (S_x - s Iw_x) / Iw.
        const float s_x = (r.s_w[1] - s * r.inv_w[1]) / iw, s_y = (r.s_w[2] - s * r.inv_w[2]) / iw;
        const float t_x = (r.t_w[1] - t * r.inv_w[1]) / iw, t_y = (r.t_w[2] - t * r.inv_w[2]) / iw;
        const float rho = std::max(std::sqrt(s_x * s_x + t_x * t_x), std::sqrt(s_y * s_y + t_y * t_y));
        lod = std::min(std::log2(std::max(rho, 1e-30f)), float(d.mip_levels - 1));
      }
      if (!(lod > 0.0f)) {
        sample_level(d, 0, s, t, 1.0f, out, true);
        continue;
      }
      const uint32_t l0 = uint32_t(std::floor(lod)), l1 = std::min(l0 + 1, d.mip_levels - 1);
      const float f = lod - float(l0);
      sample_level(d, l0, s, t, 1.0f - f, out, true);
      sample_level(d, l1, s, t, f, out, false);
    }
}

}  // namespace mesh

void size_mesh_renders(const MeshRenderDesc& d, MeshRenders& out) {
  check_mesh_render(d);
  out.width = d.width, out.height = d.height, out.count = uint32_t(d.cameras.size()), out.channels = d.channels;
  const size_t n = size_t(d.width) * d.height;
  out.coverage.resize(n * out.count);
  out.pixels.resize(n * out.count * d.channels);
}

void Engine::render_mesh(const MeshRenderDesc& d, MeshRenders& out) {
  size_mesh_renders(d, out);
  const size_t n = size_t(d.width) * d.height;
  const uint32_t tx = mesh::tiles_x(d), ty = mesh::tiles_y(d);
  std::vector<mesh::ViewSetup> setups(out.count);
  const unsigned threads = std::max(1u, device().backend == "cpu" ? device().threads : std::thread::hardware_concurrency());
  // Work items: view set-ups, then tile rows of every view; results depend only on the item.
  parallel_for(out.count, threads, [&](uint32_t v) { setups[v] = mesh::setup_view(d, v); }, 1);
  parallel_for(out.count * ty, threads, [&](uint32_t item) {
    const uint32_t v = item / ty, row = item % ty;
    for (uint32_t a = 0; a < tx; ++a)
      mesh::shade_tile(d, setups[v], a, row, out.coverage.data() + v * n, out.pixels.data() + v * n * d.channels);
  }, 1);
}

}  // namespace uvpress::engine
