// A candidate Jacobian's texture tile, fitted by least squares to the reference render
// (eq. 11), rendered and scored (mirrors view_score.comp).
#include "gmsd.h"
#include "views.h"

#include <algorithm>
#include <cmath>

namespace uvpress::engine::cpu {

namespace {

// x >= 0 here (bilinear weights, luminance), so truncation is floor: the GLSL twin's
// floor(x * Q + 0.5) gives the same integer, without the slow SSE2 floor emulation.
int32_t fixed(float x) { return int32_t(x * kFixedPoint + 0.5f); }

// Floor of a non-negative tile coordinate.
inline uint32_t cell(float a) { return uint32_t(a); }

// Stencil slot of texel b relative to texel a (|di|, |dj| <= 1): 0..8.
inline uint32_t slot(int32_t di, int32_t dj) { return uint32_t((di + 1) + 3 * (dj + 1)); }

}  // namespace

TileMap map_to_tile(const ViewDesc& view, const ViewTriangle* tris, uint32_t size, const uint8_t* coverage,
                    const float j[4]) {
  TileMap m;
  std::vector<float> u, v;
  float u_lo = INFINITY, u_hi = -INFINITY, v_lo = INFINITY, v_hi = -INFINITY;
  for (uint32_t p = 0; p < size * size; ++p) {
    if (coverage[p] == shader::kNoTriangle) continue;
    const ViewTriangle& t = tris[view.first_triangle + coverage[p]];
    float cx = float(p % size) + 0.5f, cy = float(p / size) + 0.5f;
    float s = t.s[0] + t.s[1] * cx;
    s += t.s[2] * cy;
    float tt = t.t[0] + t.t[1] * cx;
    tt += t.t[2] * cy;
    float ds = s - view.center_s, dt = tt - view.center_t;
    float pu = j[0] * ds;
    pu += j[1] * dt;
    float pv = j[2] * ds;
    pv += j[3] * dt;
    m.pixel.push_back(p);
    u.push_back(pu), v.push_back(pv);
    u_lo = std::min(u_lo, pu), u_hi = std::max(u_hi, pu), v_lo = std::min(v_lo, pv), v_hi = std::max(v_hi, pv);
  }
  if (m.pixel.empty()) return m;
  // The tile never exceeds kTileMax texels a side: a coarser lattice (power of two, so the
  // scaling is exact) for candidates whose footprint would be larger. Such a view cannot
  // resolve texels finer than its pixels anyway.
  float span = std::max(u_hi - u_lo, v_hi - v_lo), inv = 1.0f;
  while (span * inv > float(shader::kTileMax - 3)) inv *= 0.5f;
  m.lattice = 1.0f / inv;
  float ou = std::floor(u_lo * inv), ov = std::floor(v_lo * inv);
  m.width = uint32_t(std::floor(u_hi * inv) - ou) + 2;
  m.height = uint32_t(std::floor(v_hi * inv) - ov) + 2;
  m.a.resize(u.size()), m.b.resize(u.size());
  for (size_t k = 0; k < u.size(); ++k) m.a[k] = u[k] * inv - ou, m.b[k] = v[k] * inv - ov;
  return m;
}

std::vector<float> bake_tile(const TileMap& m, const float* reference, uint32_t* iterations) {
  const uint32_t w = m.width, n = m.width * m.height;
  std::vector<float> x(n, 0.0f);
  if (iterations) *iterations = 0;
  if (m.pixel.empty()) return x;
  // Normal equations, accumulated in fixed point (exact and order-free).
  std::vector<int32_t> K(size_t(n) * 9, 0), R(n, 0);
  int32_t ref_sum = 0;
  for (size_t k = 0; k < m.pixel.size(); ++k) {
    float a = m.a[k], b = m.b[k];
    uint32_t i0 = cell(a), j0 = cell(b);
    float fa = a - float(i0), fb = b - float(j0);
    const float wt[4] = {(1.0f - fa) * (1.0f - fb), fa * (1.0f - fb), (1.0f - fa) * fb, fa * fb};
    const int32_t di[4] = {0, 1, 0, 1}, dj[4] = {0, 0, 1, 1};
    const float ref = reference[m.pixel[k]];
    ref_sum += fixed(ref);
    for (int p = 0; p < 4; ++p) {
      uint32_t row = (j0 + uint32_t(dj[p])) * w + i0 + uint32_t(di[p]);
      R[row] += fixed(wt[p] * ref);
      for (int q = 0; q < 4; ++q) K[size_t(row) * 9 + slot(di[q] - di[p], dj[q] - dj[p])] += fixed(wt[p] * wt[q]);
    }
  }
  const float count = float(m.pixel.size());
  const float mean = float(ref_sum) / (kFixedPoint * count);
  const float mu = kSmoothness * count / float(n);
  // A = K / Q + mu L (L the tile's 4-neighbour graph Laplacian); b = R / Q - mean rowsum(K) / Q.
  std::vector<float> A(size_t(n) * 9), diag(n), r(n), z(n), p(n), Ap(n);
  const float inv_q = 1.0f / kFixedPoint;
  for (uint32_t t = 0; t < n; ++t) {
    int32_t rowsum = 0;
    for (uint32_t s = 0; s < 9; ++s) {
      A[size_t(t) * 9 + s] = float(K[size_t(t) * 9 + s]) * inv_q;
      rowsum += K[size_t(t) * 9 + s];
    }
    const uint32_t ti = t % w, tj = t / w;
    const bool nb[4] = {ti > 0, ti + 1 < w, tj > 0, tj + 1 < m.height};  // left right up down
    const uint32_t nb_slot[4] = {slot(-1, 0), slot(1, 0), slot(0, -1), slot(0, 1)};
    for (int e = 0; e < 4; ++e)
      if (nb[e]) A[size_t(t) * 9 + 4] += mu, A[size_t(t) * 9 + nb_slot[e]] -= mu;
    diag[t] = A[size_t(t) * 9 + 4];
    float bt = float(R[t]) * inv_q;
    bt -= mean * (float(rowsum) * inv_q);
    r[t] = bt;
  }
  const int32_t h = int32_t(m.height);
  auto apply = [&](const std::vector<float>& in, std::vector<float>& out) {
    for (int32_t jj = 0; jj < h; ++jj)
      for (int32_t ii = 0; ii < int32_t(w); ++ii) {
        const uint32_t t = uint32_t(jj) * w + uint32_t(ii);
        float acc = 0.0f;
        for (int32_t dj = -1; dj <= 1; ++dj)
          for (int32_t di = -1; di <= 1; ++di) {
            int32_t i2 = ii + di, j2 = jj + dj;
            if (i2 < 0 || j2 < 0 || i2 >= int32_t(w) || j2 >= h) continue;
            acc += A[size_t(t) * 9 + slot(di, dj)] * in[uint32_t(j2) * w + uint32_t(i2)];
          }
        out[t] = acc;
      }
  };
  auto dot = [&](const std::vector<float>& a, const std::vector<float>& b) {
    float s = 0.0f;
    for (uint32_t t = 0; t < n; ++t) s += a[t] * b[t];
    return s;
  };
  // Jacobi-preconditioned conjugate gradients from x = 0.
  const float bb = dot(r, r);
  uint32_t it = 0;
  if (bb > 0.0f) {
    for (uint32_t t = 0; t < n; ++t) z[t] = r[t] / diag[t], p[t] = z[t];
    float rz = dot(r, z);
    const float stop = kBakeTolerance * kBakeTolerance * bb;
    while (it < kBakeMaxIterations) {
      ++it;
      apply(p, Ap);
      float alpha = rz / dot(p, Ap);
      for (uint32_t t = 0; t < n; ++t) x[t] += alpha * p[t], r[t] -= alpha * Ap[t];
      if (dot(r, r) <= stop) break;
      for (uint32_t t = 0; t < n; ++t) z[t] = r[t] / diag[t];
      float rz_next = dot(r, z);
      float beta = rz_next / rz;
      rz = rz_next;
      for (uint32_t t = 0; t < n; ++t) p[t] = z[t] + beta * p[t];
    }
  }
  if (iterations) *iterations = it;
  for (auto& v : x) v += mean;
  return x;
}

void render_tile(const TileMap& m, const std::vector<float>& tile, uint32_t size, float* candidate) {
  std::fill(candidate, candidate + size_t(size) * size, 0.0f);
  for (size_t k = 0; k < m.pixel.size(); ++k) {
    float a = m.a[k], b = m.b[k];
    uint32_t i0 = cell(a), j0 = cell(b);
    float fa = a - float(i0), fb = b - float(j0);
    const float* t0 = &tile[size_t(j0) * m.width + i0];
    const float* t1 = t0 + m.width;
    float top = (1.0f - fa) * t0[0];
    top += fa * t0[1];
    float bottom = (1.0f - fa) * t1[0];
    bottom += fa * t1[1];
    float v = (1.0f - fb) * top;
    v += fb * bottom;
    candidate[m.pixel[k]] = v;
  }
}

float score_view(const ViewDesc& view, const ViewTriangle* tris, uint32_t size, const uint8_t* coverage,
                 const float* reference, const float j[4], float* candidate) {
  TileMap m = map_to_tile(view, tris, size, coverage, j);
  render_tile(m, bake_tile(m, reference), size, candidate);
  return gmsd<float>(reference, candidate, size, size);
}

}  // namespace uvpress::engine::cpu
