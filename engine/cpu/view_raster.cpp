// Deterministic rasterization of a per-triangle view (shared by view_prepare.comp).
#include "views.h"

#include <algorithm>
#include <cmath>

namespace uvpress::engine::cpu {

namespace {

// 4 sub-pixel bits. floor(v * 16 + 0.5): the same rounding in GLSL and C++.
int32_t snap(float v) { return int32_t(std::floor(v * 16.0f + 0.5f)); }

// Edge function of a -> b at p, all in 1/16 pixels; |coordinates| < 2^14 keeps it in int32.
int32_t edge(int32_t ax, int32_t ay, int32_t bx, int32_t by, int32_t px, int32_t py) {
  return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

// Top-left rule for edges of a positively oriented triangle: of two triangles sharing an
// edge (traversed in opposite directions) exactly one owns the pixels on it.
bool owns_edge(int32_t ax, int32_t ay, int32_t bx, int32_t by) {
  int32_t dx = bx - ax, dy = by - ay;
  return dy > 0 || (dy == 0 && dx < 0);
}

float bilinear_clamped(const float* tex, uint32_t w, uint32_t h, float s, float t) {
  s = std::min(std::max(s, 0.0f), float(w - 1));
  t = std::min(std::max(t, 0.0f), float(h - 1));
  float fs0 = std::floor(s), ft0 = std::floor(t);
  uint32_t i0 = uint32_t(fs0), j0 = uint32_t(ft0);
  uint32_t i1 = std::min(i0 + 1, w - 1), j1 = std::min(j0 + 1, h - 1);
  float fs = s - fs0, ft = t - ft0;
  float top = (1.0f - fs) * tex[size_t(j0) * w + i0];
  top += fs * tex[size_t(j0) * w + i1];
  float bottom = (1.0f - fs) * tex[size_t(j1) * w + i0];
  bottom += fs * tex[size_t(j1) * w + i1];
  float v = (1.0f - ft) * top;
  v += ft * bottom;
  return v;
}

}  // namespace

void rasterize_view(const ViewDesc& view, const ViewTriangle* tris, uint32_t size, const float* texture,
                    uint32_t tw, uint32_t th, uint8_t* coverage, float* reference) {
  const size_t n = size_t(size) * size;
  std::fill(coverage, coverage + n, uint8_t(shader::kNoTriangle));
  std::vector<float> depth(n, 0.0f);
  for (uint32_t k = 0; k < view.triangle_count; ++k) {
    const ViewTriangle& t = tris[view.first_triangle + k];
    int32_t x0 = snap(t.xy[0]), y0 = snap(t.xy[1]), x1 = snap(t.xy[2]), y1 = snap(t.xy[3]), x2 = snap(t.xy[4]),
            y2 = snap(t.xy[5]);
    int32_t area = edge(x0, y0, x1, y1, x2, y2);
    if (area == 0) continue;
    if (area < 0) std::swap(x1, x2), std::swap(y1, y2);
    // Pixel range of the bounding box: centres (16 i + 8) within [min, max].
    int32_t lo_x = std::min({x0, x1, x2}), hi_x = std::max({x0, x1, x2});
    int32_t lo_y = std::min({y0, y1, y2}), hi_y = std::max({y0, y1, y2});
    int32_t i_lo = std::max(0, (lo_x - 8 + 15) >> 4), i_hi = std::min(int32_t(size) - 1, (hi_x - 8) >> 4);
    int32_t j_lo = std::max(0, (lo_y - 8 + 15) >> 4), j_hi = std::min(int32_t(size) - 1, (hi_y - 8) >> 4);
    const bool own0 = owns_edge(x1, y1, x2, y2), own1 = owns_edge(x2, y2, x0, y0), own2 = owns_edge(x0, y0, x1, y1);
    for (int32_t j = j_lo; j <= j_hi; ++j)
      for (int32_t i = i_lo; i <= i_hi; ++i) {
        int32_t px = 16 * i + 8, py = 16 * j + 8;
        int32_t e0 = edge(x1, y1, x2, y2, px, py), e1 = edge(x2, y2, x0, y0, px, py), e2 = edge(x0, y0, x1, y1, px, py);
        if (e0 < 0 || e1 < 0 || e2 < 0 || (e0 == 0 && !own0) || (e1 == 0 && !own1) || (e2 == 0 && !own2)) continue;
        float cx = float(i) + 0.5f, cy = float(j) + 0.5f;
        float z = t.depth[0] + t.depth[1] * cx;
        z += t.depth[2] * cy;
        size_t p = size_t(j) * size + size_t(i);
        // The first covering triangle, then any strictly nearer one: ties keep the earlier.
        if (coverage[p] == shader::kNoTriangle || z > depth[p]) depth[p] = z, coverage[p] = uint8_t(k);
      }
  }
  for (uint32_t j = 0; j < size; ++j)
    for (uint32_t i = 0; i < size; ++i) {
      size_t p = size_t(j) * size + i;
      if (coverage[p] == shader::kNoTriangle) {
        reference[p] = 0.0f;
        continue;
      }
      const ViewTriangle& t = tris[view.first_triangle + coverage[p]];
      float cx = float(i) + 0.5f, cy = float(j) + 0.5f;
      float s = t.s[0] + t.s[1] * cx;
      s += t.s[2] * cy;
      float tt = t.t[0] + t.t[1] * cx;
      tt += t.t[2] * cy;
      reference[p] = bilinear_clamped(texture, tw, th, s, tt);
    }
}

}  // namespace uvpress::engine::cpu
