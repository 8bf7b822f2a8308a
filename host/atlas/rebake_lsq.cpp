// Least-squares re-bake (rebake_lsq.h). How:
//
// rebake() (area filter) gives every new texel the mean of the source over the texel's
// footprint. A renderer then interpolates those texels bilinearly, which blurs a second
// time: rotated or non-integer-scaled charts lose detail twice. This bake instead solves
// (1) of rebake_lsq.h over the new image's texels T, the atlas-scale form of the triangle
// stage's bake (Sun et al. 2022, eq. 11; engine/cpu/view_bake.cpp). The sample points x
// are a regular k x k grid per new texel, kept where they fall inside a new-UV triangle
// (the first that contains them: the texel's owner, else the tile list's order). S(x) is
// the band-limited source: the area filter's own footprint filter
// (engine::rebake_filter_box, the same n_x by n_y bilinear samples through the triangle's
// barycentric map) applied to a new-texel-sized square centred on x; where the layout does
// not shrink the source (|J e| <= 1) that is the plain bilinear source at x's old UV, so an
// identity layout has the source texels as an exact, zero-residual solution. The membrane
// (second term) only regularizes texels that samples constrain weakly:
// g_ij = max(g_i, g_j), g = 1 - min(1, d / (4 mu')) with d the texel's diagonal of the data
// term's normal matrix (its squared bilinear weights summed over the samples) and
// mu' = mu x samples / unknowns as in view_bake.cpp; a texel with d >= 4 mu' (every chart
// texel, a ring texel along an edge) carries none of its own, so interior texels are not
// biased and an identity layout stays exact.
//
// Unknowns are the texels some kept sample's bilinear footprint touches (covered texels
// and their 1-texel ring, wrapped by the sampler's wrap modes); every other texel keeps
// the area-filtered bake's value, and the gutter is refilled from the nearest unknown (the
// same distance transform as rebake). The normal equations (9-point stencil per unknown)
// are assembled in a fixed order (rows in three interleaved phases) and solved by Jacobi-
// preconditioned conjugate gradients per channel, started from the area-filtered bake (the
// start and the oracle: the result never has a larger objective (1) than it). Reductions
// are in fixed blocks summed in order: the bytes do not depend on the OpenMP thread count.
//
// Colour textures are solved in linear light (rebake's decode/encode tables), straight
// (the target of a texture with alpha is the premultiplied filter divided by alpha, as the
// area bake computes it), alpha as data; data textures as stored; each channel clamped to
// [0, 1] after. Normal maps keep the area-filtered bake (a least-squares fit of unit
// vectors would need the rotation and renormalization inside the objective).
//
// LsqBakeOptions::target_cell: measured as written over 20 views at half the texels, the
// sharper target (0, the sample's own cell) loses: demo q 0.0333 vs 0.0311, Duck 0.00089 vs
// 0.00068 (it aliases what the new texels cannot hold).
#include "atlas/rebake_lsq.h"

#include "core/stopwatch.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace uvpress::atlas {

namespace {

using Tri = engine::RebakeTriangle;

// Stencil slot of a neighbour at offset (dx, dy), dx, dy in {-1, 0, 1}: 4 is the texel itself.
inline int slot(int dx, int dy) { return (dy + 1) * 3 + (dx + 1); }

// Offset of physical texel q from p along an axis of n texels, in {-1, 0, 1}: taps across a
// REPEAT seam are neighbours (n - 1 apart in memory); clamped or mirrored taps coincide.
inline int axis_offset(int q, int p, int n) {
  int d = q - p;
  if (d > 1) d -= n;
  if (d < -1) d += n;
  return d;
}

// Fixed-order sums: blocks of kBlock unknowns, each summed in order by whichever thread,
// then the blocks in order, so the result does not depend on the thread count.
constexpr int64_t kBlock = 4096;

// A texel is weak when its normal-matrix diagonal d (the sum of its squared bilinear
// weights over the samples) is below kWeak mu': its membrane share g = 1 - d / (kWeak mu')
// falls linearly to 0 there. Texels the samples determine (d above that: every texel of a
// chart, ~2.6^2 inside at k = 4, and a ring texel along an edge, ~0.4) carry none, so an
// identity layout keeps its exact solution; a texel the samples barely touch is tied to its
// neighbours instead of taking whatever value a near-null direction of the data allows.
constexpr double kWeak = 4.0;

}  // namespace

Image rebake_least_squares(const Image& source, const std::vector<RebakeMesh>& meshes, const RebakeOptions& opt,
                           const Image& area, LsqBakeStats* stats, const LsqBakeOptions& lsq,
                           const std::vector<uint8_t>* keep) {
  const Stopwatch t_start;
  if (area.width != opt.width || area.height != opt.height || area.channels != source.channels ||
      area.pixels.size() != size_t(area.width) * area.height * area.channels)
    throw std::invalid_argument("rebake_least_squares: the area-filtered bake does not match the options and source");
  if (keep && keep->size() != size_t(area.width) * area.height)
    throw std::invalid_argument("rebake_least_squares: the kept-texel mask does not match the image");
  LsqBakeStats st;
  auto finish = [&](Image&& img) {
    st.seconds = t_start.seconds();
    if (stats) *stats = st;
    return std::move(img);
  };
  Image out = area;
  // Normal maps: the fit would have to include the per-triangle rotation and the unit
  // length; the area bake (rotated, renormalized) is kept.
  if (opt.role == RebakeRole::Normal && source.channels >= 2) return finish(std::move(out));

  const RebakePlan plan = plan_rebake(source, meshes, opt);
  const engine::RebakeTexelsDesc desc = plan.desc(opt);
  const int W = plan.width, H = plan.height, C = plan.channels;
  const bool linear = plan.linear;
  const int k = std::max(2, int((std::max<uint32_t>(lsq.samples_per_axis, 2) + 1) / 2 * 2));
  const double cell = lsq.target_cell > 0 ? lsq.target_cell : 1.0 / k;  // target footprint, new texels
  constexpr int T = int(engine::kRebakeTile);
  const int tx = (W + T - 1) / T;
  const auto& tris = plan.triangles;
  const uint32_t* list = plan.tile_list.data();
  const uint32_t* start = plan.tile_start.data();

  // The triangle a sample point lies in: its texel's owner, else the first of the tile's
  // list that contains it; null outside every triangle.
  auto locate = [&](int x, int y, double px, double py, const uint32_t*& first, const uint32_t*& last) -> const Tri* {
    const int tile = (y / T) * tx + x / T;
    first = list + start[tile], last = list + start[tile + 1];
    const uint32_t own = plan.owner[size_t(y) * W + x];
    double qx, qy;
    if (own != engine::kRebakeNoOwner && engine::rebake_closest_point(tris[list[own]], px, py, qx, qy) == 0)
      return &tris[list[own]];
    for (const uint32_t* it = first; it != last; ++it) {
      const Tri& u = tris[*it];
      if (px < u.lo[0] || px > u.hi[0] || py < u.lo[1] || py > u.hi[1]) continue;
      if (engine::rebake_closest_point(u, px, py, qx, qy) == 0) return &u;
    }
    return nullptr;
  };
  // Sample (i, j) of texel (x, y); offsets (i + 0.5) / k never hit a texel centre (k even),
  // so no bilinear tap has weight 0 and the left/right half decides the footprint.
  auto point = [&](int x, int i) { return x + (i + 0.5) / k; };

  // Pass 1: which quarters of each covered texel hold kept samples (bit 1: right half,
  // bit 2: bottom half), and how many samples there are (per row, summed in order).
  std::vector<uint8_t> quarter(size_t(W) * H, 0);
  std::vector<size_t> row_samples(size_t(H), 0);
#pragma omp parallel for schedule(dynamic, 4)
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      if (plan.owner[size_t(y) * W + x] == engine::kRebakeNoOwner) continue;
      uint8_t q = 0;
      size_t n = 0;
      for (int j = 0; j < k; ++j)
        for (int i = 0; i < k; ++i) {
          const uint32_t *first, *last;
          if (!locate(x, y, point(x, i), point(y, j), first, last)) continue;
          q |= uint8_t(1u << ((2 * j >= k ? 2 : 0) + (2 * i >= k ? 1 : 0)));
          ++n;
        }
      quarter[size_t(y) * W + x] = q;
      row_samples[size_t(y)] += n;
    }
  for (size_t n : row_samples) st.samples += n;
  if (st.samples == 0) return finish(std::move(out));

  // Unknowns: every texel a kept sample's bilinear footprint touches, in scan order.
  auto wx = [&](int x) { return engine::rebake_wrap(x, W, opt.wrap_s); };
  auto wy = [&](int y) { return engine::rebake_wrap(y, H, opt.wrap_t); };
  std::vector<int32_t> index(size_t(W) * H, -1);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const uint8_t q = quarter[size_t(y) * W + x];
      for (int b = 0; b < 4; ++b) {
        if (!(q & (1u << b))) continue;
        const int rx = b & 1, ry = b >> 1;
        for (int dy = -1 + ry; dy <= ry; ++dy)
          for (int dx = -1 + rx; dx <= rx; ++dx) index[size_t(wy(y + dy)) * W + wx(x + dx)] = 0;
      }
    }
  std::vector<int32_t> px_of, py_of;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      if (index[size_t(y) * W + x] == 0) {
        index[size_t(y) * W + x] = int32_t(px_of.size());
        px_of.push_back(x), py_of.push_back(y);
      }
  const int64_t N = int64_t(px_of.size());
  st.unknowns = size_t(N);
  // The 3 x 3 neighbours of every unknown through the wrap modes (-1: not an unknown).
  std::vector<int32_t> nb(size_t(N) * 9);
#pragma omp parallel for schedule(static)
  for (int64_t u = 0; u < N; ++u)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        nb[size_t(u) * 9 + slot(dx, dy)] = index[size_t(wy(py_of[u] + dy)) * W + wx(px_of[u] + dx)];

  // Pass 2: the normal equations K T = b of the data term, and sum S^2 (for E). A row of
  // texels writes rows y - 1 .. y + 1: rows three apart run in parallel, phase by phase, so
  // every entry receives its terms in the same order whatever the thread count; the rows
  // whose taps may wrap across the image's top/bottom seam run alone, in order.
  std::vector<double> K(size_t(N) * 9, 0.0), b(size_t(N) * C, 0.0);
  std::vector<double> row_ss(size_t(H), 0.0);
  auto assemble_row = [&](int y) {
    double S[4], ss = 0;
    for (int x = 0; x < W; ++x) {
      if (!quarter[size_t(y) * W + x]) continue;
      for (int j = 0; j < k; ++j)
        for (int i = 0; i < k; ++i) {
          const double sx = point(x, i), sy = point(y, j);
          const uint32_t *first, *last;
          const Tri* t = locate(x, y, sx, sy, first, last);
          if (!t) continue;
          // S(x): the area filter over the sample's own cell (target_cell new texels a side,
          // centred on it): the source itself at the sample density, so the solve is the L2
          // projection of the source onto bilinear texels (target_cell 1: the band-limited
          // source a new texel wide, i.e. what the area bake approximates).
          engine::rebake_filter_box(desc, *t, first, last, sx - 0.5 * cell, sy - 0.5 * cell, S, cell);
          for (int c = 0; c < C; ++c) ss += S[c] * S[c];
          const double fx = std::floor(sx - 0.5), fy = std::floor(sy - 0.5);
          const double ax = sx - 0.5 - fx, ay = sy - 0.5 - fy;
          const int X[2] = {wx(int(fx)), wx(int(fx) + 1)}, Y[2] = {wy(int(fy)), wy(int(fy) + 1)};
          const double w[4] = {(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay};
          for (int p = 0; p < 4; ++p) {
            const int px = X[p & 1], py = Y[p >> 1];
            const int32_t row = index[size_t(py) * W + px];
            double* Kr = &K[size_t(row) * 9];
            for (int c = 0; c < C; ++c) b[size_t(row) * C + c] += w[p] * S[c];
            for (int q = 0; q < 4; ++q)
              Kr[slot(axis_offset(X[q & 1], px, W), axis_offset(Y[q >> 1], py, H))] += w[p] * w[q];
          }
        }
    }
    row_ss[size_t(y)] = ss;
  };
  const int seam = H < 9 ? H : 3;  // rows [0, seam) and [H - seam, H) run alone
  for (int y = 0; y < seam; ++y) assemble_row(y);
  for (int phase = 0; phase < 3; ++phase) {
    const int first_row = seam + phase, last_row = H - seam;
#pragma omp parallel for schedule(dynamic, 1)
    for (int y = first_row; y < last_row; y += 3) assemble_row(y);
  }
  for (int y = std::max(seam, H - seam); y < H; ++y) assemble_row(y);
  double sum_ss = 0;
  for (double v : row_ss) sum_ss += v;

  // The membrane on weakly constrained texels: edge weight mu' g_ij (see the header), 4-
  // neighbour edges between unknowns inside the image.
  {
    const double mu = lsq.mu * double(st.samples) / double(N);
    std::vector<double> g(static_cast<size_t>(N));
    for (int64_t u = 0; u < N; ++u)
      g[size_t(u)] = 1.0 - std::clamp(K[size_t(u) * 9 + 4] / (kWeak * mu), 0.0, 1.0);
#pragma omp parallel for schedule(static)
    for (int64_t u = 0; u < N; ++u) {
      const int x = px_of[u], y = py_of[u];
      const int ds[4][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}};
      for (auto& d : ds) {
        const int nx = x + d[0], ny = y + d[1];
        if (nx < 0 || ny < 0 || nx >= W || ny >= H) continue;
        const int32_t v = index[size_t(ny) * W + nx];
        if (v < 0) continue;
        const double we = mu * std::max(g[size_t(u)], g[size_t(v)]);
        K[size_t(u) * 9 + 4] += we;
        K[size_t(u) * 9 + slot(d[0], d[1])] -= we;
      }
    }
  }

  // Start: the area bake in the working space (linear light for colour, straight).
  const int colour_channels = plan.has_alpha ? C - 1 : C;
  std::vector<double> x(size_t(N) * C);
#pragma omp parallel for schedule(static)
  for (int64_t u = 0; u < N; ++u) {
    const float* a = &area.pixels[(size_t(py_of[u]) * W + px_of[u]) * C];
    for (int c = 0; c < C; ++c)
      x[size_t(u) * C + c] = (linear && c < colour_channels) ? srgb_decode_fast(a[c]) : double(a[c]);
  }

  // y = A v for all channels (rows independent: any thread order gives the same bytes).
  auto apply = [&](const std::vector<double>& v, std::vector<double>& r) {
#pragma omp parallel for schedule(static)
    for (int64_t u = 0; u < N; ++u) {
      double acc[4] = {0, 0, 0, 0};
      const double* Kr = &K[size_t(u) * 9];
      const int32_t* nr = &nb[size_t(u) * 9];
      for (int s = 0; s < 9; ++s) {
        if (Kr[s] == 0 || nr[s] < 0) continue;
        const double* vs = &v[size_t(nr[s]) * C];
        for (int c = 0; c < C; ++c) acc[c] += Kr[s] * vs[c];
      }
      for (int c = 0; c < C; ++c) r[size_t(u) * C + c] = acc[c];
    }
  };
  // Per-channel sums of f(u, c) in fixed blocks.
  const int64_t blocks = (N + kBlock - 1) / kBlock;
  std::vector<double> partial(size_t(blocks) * C);
  auto channel_sums = [&](auto&& f, double* sums) {
#pragma omp parallel for schedule(static)
    for (int64_t blk = 0; blk < blocks; ++blk) {
      double acc[4] = {0, 0, 0, 0};
      for (int64_t u = blk * kBlock; u < std::min(N, (blk + 1) * kBlock); ++u)
        for (int c = 0; c < C; ++c) acc[c] += f(u, c);
      for (int c = 0; c < C; ++c) partial[size_t(blk) * C + c] = acc[c];
    }
    for (int c = 0; c < C; ++c) sums[c] = 0;
    for (int64_t blk = 0; blk < blocks; ++blk)
      for (int c = 0; c < C; ++c) sums[c] += partial[size_t(blk) * C + c];
  };
  const size_t NC = size_t(N) * C;
  std::vector<double> r(NC), z(NC), p(NC), Ap(NC);
  apply(x, Ap);
  for (size_t i = 0; i < NC; ++i) r[i] = b[i] - Ap[i];
  // E(T) = T'AT - 2 b'T + sum S^2 (A with the membrane).
  auto objective = [&](const std::vector<double>& AT) {
    double e[4];
    channel_sums([&](int64_t u, int c) { return x[size_t(u) * C + c] * (AT[size_t(u) * C + c] - 2 * b[size_t(u) * C + c]); }, e);
    double sum = sum_ss;
    for (int c = 0; c < C; ++c) sum += e[c];
    return sum;
  };
  st.initial_objective = objective(Ap);
  double bb[4], rr[4], rz[4], pAp[4];
  channel_sums([&](int64_t u, int c) { return b[size_t(u) * C + c] * b[size_t(u) * C + c]; }, bb);
  channel_sums([&](int64_t u, int c) { return r[size_t(u) * C + c] * r[size_t(u) * C + c]; }, rr);
  auto norm_ratio = [&](const double* num) {
    double n = 0, d = 0;
    for (int c = 0; c < C; ++c) n += num[c], d += bb[c];
    return d > 0 ? std::sqrt(n / d) : 0.0;
  };
  st.initial_residual = norm_ratio(rr);

  // Jacobi-preconditioned conjugate gradients, the channels in lockstep; a channel stops
  // when its residual is below tolerance (its alpha and beta are then 0).
  std::vector<double> inv_diag(static_cast<size_t>(N));
  for (int64_t u = 0; u < N; ++u) {
    const double d = K[size_t(u) * 9 + 4];
    inv_diag[size_t(u)] = d > 0 ? 1.0 / d : 0.0;
  }
  bool active[4];
  for (int c = 0; c < C; ++c) active[c] = rr[c] > lsq.tolerance * lsq.tolerance * bb[c];
  auto any_active = [&] {
    for (int c = 0; c < C; ++c)
      if (active[c]) return true;
    return false;
  };
#pragma omp parallel for schedule(static)
  for (int64_t u = 0; u < N; ++u)
    for (int c = 0; c < C; ++c) {
      const size_t i = size_t(u) * C + c;
      z[i] = r[i] * inv_diag[size_t(u)], p[i] = active[c] ? z[i] : 0.0;
    }
  channel_sums([&](int64_t u, int c) { return r[size_t(u) * C + c] * z[size_t(u) * C + c]; }, rz);
  uint32_t it = 0;
  while (any_active() && it < lsq.max_iterations) {
    ++it;
    apply(p, Ap);
    channel_sums([&](int64_t u, int c) { return p[size_t(u) * C + c] * Ap[size_t(u) * C + c]; }, pAp);
    double a[4];
    for (int c = 0; c < C; ++c) a[c] = active[c] && pAp[c] > 0 ? rz[c] / pAp[c] : 0.0;
#pragma omp parallel for schedule(static)
    for (int64_t u = 0; u < N; ++u)
      for (int c = 0; c < C; ++c) {
        const size_t i = size_t(u) * C + c;
        x[i] += a[c] * p[i], r[i] -= a[c] * Ap[i];
        z[i] = r[i] * inv_diag[size_t(u)];
      }
    double rz_next[4];
    channel_sums([&](int64_t u, int c) { return r[size_t(u) * C + c] * r[size_t(u) * C + c]; }, rr);
    channel_sums([&](int64_t u, int c) { return r[size_t(u) * C + c] * z[size_t(u) * C + c]; }, rz_next);
    double beta[4];
    for (int c = 0; c < C; ++c) {
      if (active[c] && (rr[c] <= lsq.tolerance * lsq.tolerance * bb[c] || !(pAp[c] > 0))) active[c] = false;
      beta[c] = active[c] && rz[c] > 0 ? rz_next[c] / rz[c] : 0.0;
      rz[c] = rz_next[c];
    }
#pragma omp parallel for schedule(static)
    for (int64_t u = 0; u < N; ++u)
      for (int c = 0; c < C; ++c) {
        const size_t i = size_t(u) * C + c;
        p[i] = active[c] ? z[i] + beta[c] * p[i] : 0.0;
      }
  }
  st.iterations = it;
  // The true residual (not the recurrence's) for the report.
  apply(x, Ap);
  st.final_objective = objective(Ap);
  channel_sums([&](int64_t u, int c) {
    const double d = b[size_t(u) * C + c] - Ap[size_t(u) * C + c];
    return d * d;
  }, rr);
  st.final_residual = norm_ratio(rr);

  // Back to stored values, clamped; the gutter refilled from the solved texels.
  std::vector<uint8_t> solved(size_t(W) * H, 0);
#pragma omp parallel for schedule(static)
  for (int64_t u = 0; u < N; ++u) {
    const size_t t = size_t(py_of[u]) * W + px_of[u];
    float* o = &out.pixels[t * C];
    for (int c = 0; c < C; ++c) {
      float v = float(std::clamp(x[size_t(u) * C + c], 0.0, 1.0));
      if (linear && c < colour_channels) v = srgb_encode_fast(v);
      o[c] = v;
    }
    solved[t] = 1;
  }
  if (opt.fill_gutter) {
    // Texels the start covered but no sample reached (slivers) keep their value, as do the
    // texels `keep` marks (a surround, which the fill then continues: atlas::fill_ring).
    for (size_t t = 0; t < solved.size(); ++t)
      if (plan.owner[t] != engine::kRebakeNoOwner || (keep && (*keep)[t])) solved[t] = 1;
    fill_gutter(out, solved, opt.role == RebakeRole::Color, keep ? fill_ring(opt) : 1);
  }
  st.solved = true;
  return finish(std::move(out));
}

}  // namespace uvpress::atlas
