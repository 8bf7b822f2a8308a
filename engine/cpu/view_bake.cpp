// A candidate Jacobian's texture tile, fitted by least squares to the reference render
// (eq. 11), rendered and scored (mirrors view_score.comp).
#include "gmsd.h"
#include "views.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace uvpress::engine::cpu {

namespace {

// x >= 0 here (bilinear weights, luminance), so truncation is floor: the GLSL twin's
// floor(x * Q + 0.5) gives the same integer, without the slow SSE2 floor emulation.
int32_t fixed(float x) { return int32_t(x * kFixedPoint + 0.5f); }

// Floor of a non-negative tile coordinate.
inline uint32_t cell(float a) { return uint32_t(a); }

// Stencil slot of texel b relative to texel a (|di|, |dj| <= 1): 0..8.
inline uint32_t slot(int32_t di, int32_t dj) { return uint32_t((di + 1) + 3 * (dj + 1)); }

// Eight texels, lane l holding texel 8c + l: each lane does the scalar operations in the
// same order (GCC's vector extension; -ffp-contract=off fuses nothing), so CG's sums keep
// their lanes on any target. (The helpers are internal and inlined into both clones of
// their callers, so GCC's note that passing 32-byte vectors by value differs between
// targets, -Wpsabi, concerns no call that exists: ignored in this file.)
#pragma GCC diagnostic ignored "-Wpsabi"
template <class T>
struct Lanes;
template <>
struct Lanes<float> {
  typedef float type __attribute__((vector_size(32)));
};
template <>
struct Lanes<int32_t> {
  typedef int32_t type __attribute__((vector_size(32)));
};
typedef Lanes<float>::type f8;
typedef Lanes<int32_t>::type i8;
// Eight values from or to memory at any alignment.
template <class T>
inline typename Lanes<T>::type load8(const T* at) {
  typename Lanes<T>::type v;
  std::memcpy(&v, at, sizeof v);
  return v;
}
template <class T>
inline void store8(T* at, typename Lanes<T>::type v) {
  std::memcpy(at, &v, sizeof v);
}
// fixed() of each lane.
inline i8 fixed8(f8 x) { return __builtin_convertvector(x * kFixedPoint + 0.5f, i8); }
// The lanes' partial sums added in a fixed order.
inline float sum8(f8 part) { return ((part[0] + part[1]) + (part[2] + part[3])) + ((part[4] + part[5]) + (part[6] + part[7])); }

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

__attribute__((target_clones("avx2", "default")))
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
    const float ds = v.ds[k], dt = v.dt[k];
    float pu = j[0] * ds;
    pu += j[1] * dt;
    float pv = j[2] * ds;
    pv += j[3] * dt;
    u[k] = pu, w[k] = pv;
  }
  // Each group's bounds over its runs of pixels (raster order keeps a group's pixels
  // together), 8 lanes a run in registers: min and max are exact, so any order gives the
  // same bounds (up to the sign of a zero bound, which changes no texel placement below).
  // Bounds kept in arrays indexed by group made each pixel wait for the last one's store.
  for (size_t k = 0; k < count;) {
    const uint32_t g = v.group[k];
    size_t end = k + 1;
    while (end < count && v.group[end] == g) ++end;
    f8 lu = f8{} + INFINITY, hu = f8{} - INFINITY, lv = lu, hv = hu;
    for (; k + 8 <= end; k += 8) {
      const f8 a = load8(&u[k]), b = load8(&w[k]);
      lu = a < lu ? a : lu, hu = a > hu ? a : hu, lv = b < lv ? b : lv, hv = b > hv ? b : hv;
    }
    for (uint32_t l = 0; l < 8; ++l)
      lo_u[g] = std::min(lo_u[g], lu[l]), hi_u[g] = std::max(hi_u[g], hu[l]), lo_v[g] = std::min(lo_v[g], lv[l]),
      hi_v[g] = std::max(hi_v[g], hv[l]);
    for (; k < end; ++k)
      lo_u[g] = std::min(lo_u[g], u[k]), hi_u[g] = std::max(hi_u[g], u[k]), lo_v[g] = std::min(lo_v[g], w[k]),
      hi_v[g] = std::max(hi_v[g], w[k]);
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
  // Normal equations in fixed point (exact and order-free), in two steps. Each pixel adds
  // its 10 distinct products w_p w_q of its 4 bilinear weights (corners p = 00, 10, 01, 11)
  // and its 4 w_p ref to its cell's 16 sums, two vector additions: adding the 20 terms to
  // the 4 texels' rows directly took 20 scattered read-modify-writes a pixel and was the
  // largest part of the bake. Then each texel gathers its row from the 4 cells it is a
  // corner of (the same integers, so the same sums).
  const uint32_t margin = w + 1;  // cells before texel 0's, read (as zeros) by the first row
  std::vector<int32_t> cells(16 * (size_t(n) + margin), 0);
  int32_t* const C = cells.data() + 16 * size_t(margin);  // cell (i, j)'s 16 sums at C[16 (j w + i)]
  int32_t ref_sum = 0;
  for (size_t k = 0; k < m.pixel.size(); ++k) {
    float a = m.a[k], b = m.b[k];
    uint32_t i0 = cell(a), j0 = cell(b);
    float fa = a - float(i0), fb = b - float(j0);
    const float w0 = (1.0f - fa) * (1.0f - fb), w1 = fa * (1.0f - fb), w2 = (1.0f - fa) * fb, w3 = fa * fb;
    const float ref = reference[m.pixel[k]];
    ref_sum += fixed(ref);
    // Lanes: 00 01 02 03 11 12 13 22 | 23 33 r0 r1 r2 r3 - - (pq: w_p w_q, rp: w_p ref).
    const f8 lo = f8{w0, w0, w0, w0, w1, w1, w1, w2} * f8{w0, w1, w2, w3, w1, w2, w3, w2};
    const f8 hi = f8{w2, w3, w0, w1, w2, w3, 0.0f, 0.0f} * f8{w3, w3, ref, ref, ref, ref, 0.0f, 0.0f};
    int32_t* c = C + 16 * (size_t(j0) * w + i0);
    store8(c, load8(c) + fixed8(lo)), store8(c + 8, load8(c + 8) + fixed8(hi));
  }
  // Texel t is corner 00 of cell t, 10 of t - 1, 01 of t - w and 11 of t - w - 1 (a cell
  // across the tile's edge, or of the last row or column, holds zeros).
  struct Corners {
    const int32_t *c00, *c10, *c01, *c11;
  };
  auto corners = [&](uint32_t t) {
    const int32_t* c00 = C + 16 * size_t(t);
    return Corners{c00, c00 - 16, c00 - 16 * size_t(w), c00 - 16 * size_t(w) - 16};
  };
  // A texel no pixel sees is left out (an identity row, x = 0): it cannot change the
  // render, and left in it would only add the membrane's smooth, nearly singular modes.
  std::vector<uint8_t> seen(n);
  uint32_t seen_count = 0;
  for (uint32_t t = 0; t < n; ++t) {
    const auto [c00, c10, c01, c11] = corners(t);
    seen[t] = c00[0] + c10[4] + c01[7] + c11[9] != 0, seen_count += seen[t];
  }
  const float count = float(m.pixel.size());
  const float mean = float(ref_sum) / (kFixedPoint * count);
  const float mu = kSmoothness * count / float(std::max(seen_count, 1u));
  // The CG system, every vector with a margin of M >= w + 1 zeros before its n texels and
  // at least M + 7 after (texel t at M + t, M a multiple of 8; the last chunk's lanes may
  // pass n by 7), so the stencil reads its 9 neighbours without bounds checks and a texel
  // keeps its lane t mod 8. A neighbour across the tile's left or right edge is the row
  // before's last texel or the next row's first: A's coefficient for it is exactly 0 (the
  // bilinear footprint and the membrane stay in the tile), so its term adds A * p = 0, as
  // a padded zero would.
  // A = K / Q + mu L (L the 4-neighbour graph Laplacian of the seen texels);
  // b = R / Q - mean rowsum(K) / Q. A is stored as 9 planes (slot s of texel t at s * N +
  // M + t), so that the stencil product runs along the texels in vector registers.
  const uint32_t h = m.height, M = (w + 1 + 7) / 8 * 8;
  const size_t N = (size_t(n) + 2 * M + 8 + 15) / 16 * 16;  // one vector, margins included, 64-byte multiple
  // One allocation: A's 9 planes, then diag, r, z, p, Ap and x, each starting on a 64-byte
  // line (the chunks' loads and stores of A and of the vectors split no cache line).
  std::vector<float> storage(15 * N + 16, 0.0f);
  float* const A = storage.data() + (16 - (reinterpret_cast<uintptr_t>(storage.data()) / 4) % 16) % 16;
  float *const diag = A + 9 * N, *const r = diag + N, *const z = r + N, *const p = z + N, *const Ap = p + N,
               *const xm = Ap + N;
  std::fill(diag, diag + N, 1.0f);
  const float inv_q = 1.0f / kFixedPoint;
  for (uint32_t t = 0; t < n; ++t) {
    const size_t at = M + t;
    if (!seen[t]) {  // the identity row, right-hand side 0
      A[size_t(4) * N + at] = 1.0f;
      continue;
    }
    // The texel's row of K and R: the sums of its 4 cells' terms.
    const auto [c00, c10, c01, c11] = corners(t);
    const int32_t k[9] = {c11[3],         c01[2] + c11[6],
                          c01[5],         c10[1] + c11[8],
                          c00[0] + c10[4] + c01[7] + c11[9],
                          c00[1] + c01[8], c10[5],
                          c00[2] + c10[6], c00[3]};  // slot(di, dj) order
    const int32_t R = c00[10] + c10[11] + c01[12] + c11[13];
    int32_t rowsum = 0;
    for (uint32_t s = 0; s < 9; ++s) A[size_t(s) * N + at] = float(k[s]) * inv_q, rowsum += k[s];
    const uint32_t ti = t % w, tj = t / w;
    const bool nb[4] = {ti > 0 && seen[t - 1], ti + 1 < w && seen[t + 1], tj > 0 && seen[t - w],
                        tj + 1 < m.height && seen[t + w]};  // left right up down
    const uint32_t nb_slot[4] = {slot(-1, 0), slot(1, 0), slot(0, -1), slot(0, 1)};
    for (int e = 0; e < 4; ++e)
      if (nb[e]) A[size_t(4) * N + at] += mu, A[size_t(nb_slot[e]) * N + at] -= mu;
    diag[at] = A[size_t(4) * N + at];
    float bt = float(R) * inv_q;
    bt -= mean * (float(rowsum) * inv_q);
    r[at] = bt;
  }
  // Every CG vector stays 0 at the unseen texels (their row of A is the identity and their
  // right-hand side 0) and in the margins, and half of a tile's texels are unseen on the
  // shared assets (a triangle fills half of its box; Fox: 1,286 texels a tile, 597 seen).
  // So the loops visit only the 8-texel chunks that hold a seen texel, and the chunk that
  // holds the last texels (its lanes past n are margin). A sum keeps its lanes (t mod 8) and
  // order; it only skips terms that are exactly 0, which leave a partial sum as it was, so
  // the bits are those of loops over all texels.
  std::vector<uint32_t> chunks;  // chunks c (texels 8c .. 8c + 7) holding a seen texel, ascending
  for (uint32_t jj = 0; jj < h; ++jj) {
    const uint8_t* row = &seen[size_t(jj) * w];
    uint32_t a = 0, b = w;
    while (a < w && !row[a]) ++a;
    while (b > a && !row[b - 1]) --b;
    if (a == b) continue;
    for (uint32_t c = (jj * w + a) / 8; c <= (jj * w + b - 1) / 8; ++c)
      if (chunks.empty() || chunks.back() < c) chunks.push_back(c);
  }
  if (n % 8 != 0 && (chunks.empty() || chunks.back() < n / 8)) chunks.push_back(n / 8);
  const float* const plane[9] = {A + M,         A + N + M,     A + 2 * N + M, A + 3 * N + M, A + 4 * N + M,
                                 A + 5 * N + M, A + 6 * N + M, A + 7 * N + M, A + 8 * N + M};
  const ptrdiff_t W = ptrdiff_t(w);
  const ptrdiff_t offset[9] = {-W - 1, -W, -W + 1, -1, 0, 1, W - 1, W, W + 1};
  float* __restrict pv = p + M;
  float* __restrict apv = Ap + M;
  float* __restrict xv = xm + M;
  float* __restrict rv = r + M;
  float* __restrict zv = z + M;
  const float* __restrict dv = diag + M;
  // p = z + beta p over every chunk first (stored just before the stencil's unaligned loads
  // of it, p stalled their store forwarding: slower than a separate pass), then one pass:
  // Ap = A p (per texel the 9 products in slot order, the GLSL twin's) and p . Ap in 8
  // partial sums (lanes), returned.
  auto step_p_apply = [&](float beta) {
    f8 part = {};
    for (const uint32_t c : chunks) store8(pv + 8 * c, load8(zv + 8 * c) + beta * load8(pv + 8 * c));
    for (size_t k = 0; k < chunks.size(); ++k) {
      const uint32_t i = 8 * chunks[k];
      f8 acc = {};
      for (uint32_t s = 0; s < 9; ++s) acc += load8(plane[s] + i) * load8(pv + i + offset[s]);
      store8(apv + i, acc);
      part += load8(pv + i) * acc;
    }
    return sum8(part);
  };
  // One pass: x += alpha p, r -= alpha A p, z = D^-1 r, and r . z in lanes, returned.
  auto step_r = [&](float alpha) {
    f8 part = {};
    for (const uint32_t c : chunks) {
      const uint32_t i = 8 * c;
      store8(xv + i, load8(xv + i) + alpha * load8(pv + i));
      const f8 ri = load8(rv + i) - alpha * load8(apv + i), zi = ri / load8(dv + i);
      store8(rv + i, ri), store8(zv + i, zi);
      part += ri * zi;
    }
    return sum8(part);
  };
  // Jacobi-preconditioned conjugate gradients from x = 0, until the last kBakeDelay terms
  // alpha_i (r_i . z_i) of the A-norm error (views.h) sum to at most the render tolerance.
  uint32_t it = 0;
  float rz;
  {
    f8 part = {};
    for (uint32_t t = 0; t < n; ++t) zv[t] = rv[t] / dv[t], part[t % 8] += rv[t] * zv[t];
    rz = sum8(part);
  }
  if (rz > 0.0f) {
    const float stop = kBakeRenderTolerance * kBakeRenderTolerance * count;
    float error[kBakeDelay] = {};
    static_assert(kBakeDelay == 4, "the sum below is written out for a delay of 4");
    float beta = 0.0f;  // p = z on the first pass
    while (it < kBakeMaxIterations) {
      float alpha = rz / step_p_apply(beta);
      error[it % kBakeDelay] = alpha * rz;
      ++it;
      const float rz_next = step_r(alpha);
      if (it >= kBakeDelay && (error[0] + error[1]) + (error[2] + error[3]) <= stop) break;
      beta = rz_next / rz;
      rz = rz_next;
    }
  }
  std::copy_n(xv, n, x.data());
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
