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

ViewPixels view_pixels(const ViewDesc& view, const ViewTriangle* tris, uint32_t size, const uint8_t* coverage) {
  ViewPixels v;
  v.groups = std::min(std::max(view.group_count, 1u), shader::kViewMaxGroups);
  for (uint32_t p = 0; p < size * size; ++p) {
    if (coverage[p] == shader::kNoTriangle) continue;
    const ViewTriangle& t = tris[view.first_triangle + coverage[p]];
    float cx = float(p % size) + 0.5f, cy = float(p / size) + 0.5f;
    float s = t.s[0] + t.s[1] * cx;
    s += t.s[2] * cy;
    float tt = t.t[0] + t.t[1] * cx;
    tt += t.t[2] * cy;
    v.pixel.push_back(p);
    v.ds.push_back(s - t.anchor_s), v.dt.push_back(tt - t.anchor_t);
    v.group.push_back(uint8_t(std::min(t.group, v.groups - 1)));
  }
  return v;
}

TileMap map_to_tile(const ViewDesc& view, const ViewTriangle* tris, uint32_t size, const uint8_t* coverage,
                    const float j[4]) {
  return map_to_tile(view_pixels(view, tris, size, coverage), j);
}

TileMap map_to_tile(const ViewPixels& v, const float j[4]) {
  static_assert(shader::kViewMaxGroups <= 256, "groups are stored in a byte");
  TileMap m;
  const uint32_t groups = v.groups;
  const size_t count = v.pixel.size();
  std::vector<float> u(count), w(count);
  float lo_u[shader::kViewMaxGroups], hi_u[shader::kViewMaxGroups], lo_v[shader::kViewMaxGroups],
      hi_v[shader::kViewMaxGroups];
  std::fill(lo_u, lo_u + groups, INFINITY), std::fill(hi_u, hi_u + groups, -INFINITY);
  std::fill(lo_v, lo_v + groups, INFINITY), std::fill(hi_v, hi_v + groups, -INFINITY);
  for (size_t k = 0; k < count; ++k) {
    const uint32_t g = v.group[k];
    const float ds = v.ds[k], dt = v.dt[k];
    float pu = j[0] * ds;
    pu += j[1] * dt;
    float pv = j[2] * ds;
    pv += j[3] * dt;
    u[k] = pu, w[k] = pv;
    lo_u[g] = std::min(lo_u[g], pu), hi_u[g] = std::max(hi_u[g], pu);
    lo_v[g] = std::min(lo_v[g], pv), hi_v[g] = std::max(hi_v[g], pv);
  }
  m.pixel = v.pixel;
  if (m.pixel.empty()) return m;
  // One region per group, shelf-packed left to right with a texel of gap (the membrane
  // term couples regions only through it, negligibly). The lattice is J's own; only a
  // layout that would exceed kTileMax texels a side takes a coarser power of two (exact
  // scaling), and the caller is told through `lattice`.
  float inv = 1.0f, ou[shader::kViewMaxGroups] = {}, ov[shader::kViewMaxGroups] = {};
  float px[shader::kViewMaxGroups] = {}, py[shader::kViewMaxGroups] = {};
  for (;;) {
    uint32_t x = 0, y = 0, shelf = 0, width = 0;
    bool fits = true;
    for (uint32_t g = 0; g < groups && fits; ++g) {
      if (lo_u[g] > hi_u[g]) continue;  // no pixel of this group in the view
      ou[g] = std::floor(lo_u[g] * inv), ov[g] = std::floor(lo_v[g] * inv);
      // Sizes compared as floats before any cast (check_view_set bounds the planes, so
      // the halving ends after a few steps).
      const float wf = std::floor(hi_u[g] * inv) - ou[g] + 2, hf = std::floor(hi_v[g] * inv) - ov[g] + 2;
      fits = wf <= float(shader::kTileMax) && hf <= float(shader::kTileMax);
      if (!fits) break;
      const uint32_t w = uint32_t(wf), h = uint32_t(hf);
      if (x > 0 && x + w > shader::kTileMax) x = 0, y += shelf + 1, shelf = 0;
      px[g] = float(x), py[g] = float(y);
      x += w + 1, shelf = std::max(shelf, h), width = std::max(width, x - 1);
    }
    m.width = width, m.height = y + shelf;
    if (fits && m.width <= shader::kTileMax && m.height <= shader::kTileMax) break;
    inv *= 0.5f;
  }
  m.lattice = 1.0f / inv;
  m.a.resize(count), m.b.resize(count);
  for (size_t k = 0; k < count; ++k) {
    const uint32_t g = v.group[k];
    float a = u[k] * inv - ou[g], b = w[k] * inv - ov[g];
    // Inside the region by construction; the clamp only catches the rounding of a value
    // a hair below the region's last texel up onto it, at coarse lattices.
    m.a[k] = std::min(a + px[g], float(m.width) - 1.0001f), m.b[k] = std::min(b + py[g], float(m.height) - 1.0001f);
  }
  return m;
}

// Built twice and chosen at load time (GCC's function multi-versioning): with AVX2 the
// stencil product and the vector updates run 8 lanes wide (Fox's triangle stage: 9 % less
// device time). The results are the same bits on either: the engine is compiled with
// -ffp-contract=off (engine/CMakeLists.txt), so no a * b + c is fused on any target; floating
// point reductions are not reordered without -ffast-math/-fassociative-math (never to be
// added here), so each lane does what the scalar code does, in the same order (the dot
// products' 8 partial sums are lanes, added in a fixed order).
__attribute__((target_clones("avx2", "default")))
std::vector<float> bake_tile(const TileMap& m, const float* reference, uint32_t* iterations, float* mean_out) {
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
  // A texel no pixel sees is left out (an identity row, x = 0): it cannot change the
  // render, and left in it would only add the membrane's smooth, nearly singular modes.
  std::vector<uint8_t> seen(n);
  uint32_t seen_count = 0;
  for (uint32_t t = 0; t < n; ++t) seen[t] = K[size_t(t) * 9 + 4] != 0, seen_count += seen[t];
  const float count = float(m.pixel.size());
  const float mean = float(ref_sum) / (kFixedPoint * count);
  const float mu = kSmoothness * count / float(std::max(seen_count, 1u));
  // A = K / Q + mu L (L the 4-neighbour graph Laplacian of the seen texels);
  // b = R / Q - mean rowsum(K) / Q. A is stored as 9 planes of n (slot s of texel t at
  // s * n + t), so that the stencil product runs along rows in vector registers.
  std::vector<float> A(size_t(n) * 9), diag(n), r(n), z(n), Ap(n);
  const float inv_q = 1.0f / kFixedPoint;
  for (uint32_t t = 0; t < n; ++t) {
    int32_t rowsum = 0;
    for (uint32_t s = 0; s < 9; ++s) {
      const int32_t k = seen[t] ? K[size_t(t) * 9 + s] : 0;
      A[size_t(s) * n + t] = float(k) * inv_q;
      rowsum += k;
    }
    if (!seen[t]) A[size_t(4) * n + t] = 1.0f;
    const uint32_t ti = t % w, tj = t / w;
    const bool nb[4] = {ti > 0 && seen[t - 1], ti + 1 < w && seen[t + 1], tj > 0 && seen[t - w],
                        tj + 1 < m.height && seen[t + w]};  // left right up down
    const uint32_t nb_slot[4] = {slot(-1, 0), slot(1, 0), slot(0, -1), slot(0, 1)};
    for (int e = 0; e < 4; ++e)
      if (seen[t] && nb[e]) A[size_t(4) * n + t] += mu, A[size_t(nb_slot[e]) * n + t] -= mu;
    diag[t] = A[size_t(4) * n + t];
    float bt = seen[t] ? float(R[t]) * inv_q : 0.0f;
    bt -= mean * (float(rowsum) * inv_q);
    r[t] = bt;
  }
  // Every CG vector stays 0 at the unseen texels (their row of A is the identity and their
  // right-hand side 0), and half of a tile's texels are unseen on the shared assets (a
  // triangle fills half of its box; Fox: 1,286 texels a tile, 597 seen). So the loops visit
  // only each row's span of seen texels, and the flat loops the 8-texel chunks that hold
  // one. A sum keeps its lanes (t mod 8) and order; it only skips terms that are exactly 0,
  // which leave a partial sum as it was, so the bits are those of the loops over all texels.
  const uint32_t h = m.height;
  std::vector<uint32_t> lo(h, 0), hi(h, 0);  // row jj's seen texels lie in [lo, hi)
  std::vector<uint32_t> chunks;             // chunks c (texels 8c .. 8c + 7, all < n) holding a seen texel
  const uint32_t full = n / 8;              // chunks; texels from 8 full on are the tail
  for (uint32_t jj = 0; jj < h; ++jj) {
    const uint8_t* row = &seen[size_t(jj) * w];
    uint32_t a = 0, b = w;
    while (a < w && !row[a]) ++a;
    while (b > a && !row[b - 1]) --b;
    lo[jj] = a, hi[jj] = b;
    if (a == b) continue;
    for (uint32_t c = (jj * w + a) / 8; c <= (jj * w + b - 1) / 8 && c < full; ++c)
      if (chunks.empty() || chunks.back() < c) chunks.push_back(c);
  }
  // p lives in a zero-padded (w + 2) x (h + 2) tile, so the stencil reads its 9 neighbours
  // without bounds checks (the view_score.comp layout); out-of-tile terms add A * 0 = 0,
  // the same sums as skipping them.
  const uint32_t W2 = w + 2;
  std::vector<float> pp(size_t(W2) * (h + 2), 0.0f);
  const int32_t offset[9] = {-int32_t(W2) - 1, -int32_t(W2), -int32_t(W2) + 1, -1, 0, 1,
                             int32_t(W2) - 1, int32_t(W2), int32_t(W2) + 1};
  // out = A p, row by row: per texel the 9 products summed in slot order (the GLSL twin's
  // order), texels independent, so the compiler runs a row in vector lanes.
  const float* const plane[9] = {&A[0],     &A[size_t(n)], &A[2 * size_t(n)], &A[3 * size_t(n)], &A[4 * size_t(n)],
                                 &A[5 * size_t(n)], &A[6 * size_t(n)], &A[7 * size_t(n)], &A[8 * size_t(n)]};
  auto apply = [&](std::vector<float>& out) {
    for (uint32_t jj = 0; jj < h; ++jj) {
      const size_t row = size_t(jj) * w;
      const float* c = &pp[size_t(jj + 1) * W2 + 1];
      const float *c0 = c + offset[0], *c1 = c + offset[1], *c2 = c + offset[2], *c3 = c + offset[3], *c4 = c + offset[4],
                  *c5 = c + offset[5], *c6 = c + offset[6], *c7 = c + offset[7], *c8 = c + offset[8];
      const float *a0 = plane[0] + row, *a1 = plane[1] + row, *a2 = plane[2] + row, *a3 = plane[3] + row,
                  *a4 = plane[4] + row, *a5 = plane[5] + row, *a6 = plane[6] + row, *a7 = plane[7] + row,
                  *a8 = plane[8] + row;
      float* o = &out[row];
      for (uint32_t ii = lo[jj]; ii < hi[jj]; ++ii) {
        float acc = 0.0f;
        acc += a0[ii] * c0[ii];
        acc += a1[ii] * c1[ii];
        acc += a2[ii] * c2[ii];
        acc += a3[ii] * c3[ii];
        acc += a4[ii] * c4[ii];
        acc += a5[ii] * c5[ii];
        acc += a6[ii] * c6[ii];
        acc += a7[ii] * c7[ii];
        acc += a8[ii] * c8[ii];
        o[ii] = acc;
      }
    }
  };
  // Dot products in 8 interleaved partial sums added in a fixed order: deterministic, and
  // not bound by the latency of one long chain of additions.
  auto dot = [&](const float* a, const float* b) {
    float part[8] = {};
    for (const uint32_t c : chunks)
      for (uint32_t k = 0; k < 8; ++k) part[k] += a[8 * c + k] * b[8 * c + k];
    for (uint32_t t = 8 * full; t < n; ++t) part[t % 8] += a[t] * b[t];
    return ((part[0] + part[1]) + (part[2] + part[3])) + ((part[4] + part[5]) + (part[6] + part[7]));
  };
  // The two element-wise steps over the chunks and the tail (restrict: vector lanes).
  float* __restrict xv = x.data();
  float* __restrict rv = r.data();
  float* __restrict zv = z.data();
  const float* __restrict apv = Ap.data();
  const float* __restrict dv = diag.data();
  auto update = [&](float alpha) {  // x += alpha p, r -= alpha A p
    for (const uint32_t c : chunks)
      for (uint32_t k = 8 * c; k < 8 * c + 8; ++k) xv[k] += alpha * zv[k], rv[k] -= alpha * apv[k];
    for (uint32_t t = 8 * full; t < n; ++t) xv[t] += alpha * zv[t], rv[t] -= alpha * apv[t];
  };
  auto precondition = [&] {  // z = D^-1 r
    for (const uint32_t c : chunks)
      for (uint32_t k = 8 * c; k < 8 * c + 8; ++k) zv[k] = rv[k] / dv[k];
    for (uint32_t t = 8 * full; t < n; ++t) zv[t] = rv[t] / dv[t];
  };
  // Jacobi-preconditioned conjugate gradients from x = 0, until the last kBakeDelay terms
  // alpha_i (r_i . z_i) of the A-norm error (views.h) sum to at most the render tolerance.
  uint32_t it = 0;
  for (uint32_t t = 0; t < n; ++t) z[t] = r[t] / diag[t];
  float rz = dot(r.data(), z.data());
  if (rz > 0.0f) {
    for (uint32_t jj = 0; jj < h; ++jj) std::copy_n(&z[size_t(jj) * w], w, &pp[size_t(jj + 1) * W2 + 1]);
    const float stop = kBakeRenderTolerance * kBakeRenderTolerance * count;
    float error[kBakeDelay] = {};
    static_assert(kBakeDelay == 4, "the sum below is written out for a delay of 4");
    while (it < kBakeMaxIterations) {
      apply(Ap);
      // p's interior, unpadded, for the dot product and the update of x.
      for (uint32_t jj = 0; jj < h; ++jj)
        std::copy(&pp[size_t(jj + 1) * W2 + 1 + lo[jj]], &pp[size_t(jj + 1) * W2 + 1 + hi[jj]], &z[size_t(jj) * w + lo[jj]]);
      float alpha = rz / dot(z.data(), Ap.data());
      error[it % kBakeDelay] = alpha * rz;
      ++it;
      update(alpha);
      if (it >= kBakeDelay && (error[0] + error[1]) + (error[2] + error[3]) <= stop) break;
      precondition();
      float rz_next = dot(r.data(), z.data());
      float beta = rz_next / rz;
      rz = rz_next;
      for (uint32_t jj = 0; jj < h; ++jj) {
        float* p = &pp[size_t(jj + 1) * W2 + 1];
        const float* zr = &z[size_t(jj) * w];
        for (uint32_t ii = lo[jj]; ii < hi[jj]; ++ii) p[ii] = zr[ii] + beta * p[ii];
      }
    }
  }
  if (iterations) *iterations = it;
  if (mean_out) {
    *mean_out = mean;
    return x;
  }
  for (auto& v : x) v += mean;
  return x;
}

void render_tile(const TileMap& m, const std::vector<float>& tile, uint32_t size, float* candidate, float offset) {
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
    candidate[m.pixel[k]] = v + offset;
  }
}

float score_view(const ViewPixels& pixels, uint32_t size, const float* reference, const float j[4], float* candidate,
                 float* lattice) {
  TileMap m = map_to_tile(pixels, j);
  float mean = 0;
  const std::vector<float> x = bake_tile(m, reference, nullptr, &mean);
  render_tile(m, x, size, candidate, mean);
  if (lattice) *lattice = m.lattice;
  return gmsd<float>(reference, candidate, size, size);
}

}  // namespace uvpress::engine::cpu
