// Lanczos re-bake (rebake_lanczos.h). How and why:
//
// rebake() (area filter: the mean of bilinear samples over the texel's footprint) blurs
// more than the Lanczos-3 resize users compare against: on the demo at half the texels, the
// stretch-only-outline layout scores q 0.030 over eval's 20 views area-baked and 0.022
// baked by this filter (the plain resize: 0.025). This bake evaluates, per covered texel, the
// separable Lanczos-3 kernel in the new image's texel axes (where the layout shrinks the
// source, as a resize does: support 3 new texels) or in the source's (where it magnifies:
// Lanczos interpolation), through the owner triangle's map d old / d new = J = U S V^T:
// a source texel at offset d from the texel centre's preimage has kernel coordinates
// V min(S^-1, 1) U^T d. For a uniform scale that is the Lanczos-3 resize itself.
//
// Values are filtered as stored (the resize does the same: "lanczos3-srgb"), normalized by
// the kernel's sum and clamped to [0, 1] (Lanczos rings); the source is read through the
// sampler's wrap modes. A kernel reads the texels of its own chart and of the source's
// gutters (which usually continue the chart), never another chart's: in a tight atlas the
// next chart sits a few texels away, and a resize may blend it in because it stays next
// door; a reshaped layout moves it. Where a triangle squeezes the source more than 3x
// in some direction (a target shrank it to almost nothing) the texel keeps the area bake's
// value: a kernel 3 new texels wide then spans 9+ source texels, far past the small source
// triangle, and averages unrelated detail into grey (CesiumMilkTruck's paper layout at half
// the texels: q 0.0059 with every texel Lanczos, 0.0030 with the cap, 0.0030 all area).
// Normal maps keep the area bake (their vectors must be rotated with the chart).
// Texels no triangle owns keep `area`'s values (gutters); covered texels are replaced and
// the gutter refilled from them (rebake's distance transform). With options.surround = r,
// the texels within r of a chart are baked too, through the map of the triangle that owns
// the nearest chart texel: a white-backed atlas (CesiumMilkTruck) blends white into its
// dark charts' edges at coarse mip levels, in the input as in a plain resize, and a gutter
// filled with the chart's own colour instead differed from the input at every chart edge
// (its repack at half the texels, 1024-px trilinear views: q 0.0231 against the resize's
// 0.0101; bilinear views, level 0 only: 0.0075 against 0.0071). Deterministic per texel.
#include "atlas/rebake_lanczos.h"

#include "core/disjoint_sets.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

namespace uvpress::atlas {

namespace {

// Beyond this shrink in some direction a texel keeps the area bake (above).
constexpr double kMaxShrink = 3;

// Lanczos-3, 3 sin(pi k) sin(pi k / 3) / (pi k)^2 (1 at 0), tabulated at kTablePerUnit
// points per unit of |k| over [0, 3] and interpolated linearly: a tap is then a lookup, not
// two sines (4 sin calls a tap were ~60 % of this bake's time; sines stepped along the tap
// lattice by angle addition, the rule before, still ~12 % of Fox's reparam). The
// interpolation's error is below h^2 max|L''| / 8 = 1e-7 (h = 1/2048, |L''| <= pi^2 / 3 +
// pi^2 / 27 < 3.7), under the float result's rounding after normalization.
constexpr int kTablePerUnit = 2048;

struct Lanczos3Table {
  std::vector<float> v;
  Lanczos3Table() : v(3 * kTablePerUnit + 2, 0.0f) {
    for (int i = 0; i <= 3 * kTablePerUnit; ++i) {
      const double k = double(i) / kTablePerUnit, pk = M_PI * k;
      v[size_t(i)] = i == 0 ? 1.0f : float(3 * std::sin(pk) * std::sin(pk / 3) / (pk * pk));
    }
  }
  // |k| < 3.
  double operator()(double k) const {
    const double f = std::abs(k) * kTablePerUnit;
    const int i = int(f);
    const double t = f - i;
    return double(v[size_t(i)]) + t * double(v[size_t(i) + 1] - v[size_t(i)]);
  }
};

// The taps i = 0, 1, ... of a row whose kernel coordinate a + b i lies in (-3, 3), as a
// half-open interval clipped to [lo, hi); a tap or two past either end is harmless (the
// caller tests each tap), one missing is not, hence the widening by one.
inline void kernel_span(double a, double b, int& lo, int& hi) {
  if (std::abs(b) < 1e-12) {
    if (std::abs(a) >= 3) hi = lo;
    return;
  }
  double t0 = (-3 - a) / b, t1 = (3 - a) / b;
  if (t0 > t1) std::swap(t0, t1);
  const double l = lo, h = hi;  // clamped before converting: a far span must not overflow an int
  lo = int(std::clamp(std::floor(t0) - 1, l, h)), hi = int(std::clamp(std::ceil(t1) + 2, l, h));
}

// Which chart each source texel belongs to: the plan's triangles mapped back to the source
// (old corners o0 + J (n_k - n0)), grouped into charts by shared old corners, and every
// source texel centre inside one of them labelled with its chart (kShared where charts of
// the input overlap, kNone in the source's gutters).
constexpr int32_t kNone = -1, kShared = -2;

struct SourceCharts {
  std::vector<int32_t> chart_of_triangle;
  std::vector<int32_t> texel;  // source width * height
};

SourceCharts source_charts(const RebakePlan& plan, int SW, int SH) {
  SourceCharts sc;
  const size_t n = plan.triangles.size();
  std::vector<std::array<double, 6>> old(n);
  for (size_t i = 0; i < n; ++i) {
    const engine::RebakeTriangle& t = plan.triangles[i];
    for (int k = 0; k < 3; ++k) {
      const double dx = t.n[k][0] - t.n[0][0], dy = t.n[k][1] - t.n[0][1];
      old[i][2 * size_t(k)] = t.o0[0] + t.J[0][0] * dx + t.J[0][1] * dy;
      old[i][2 * size_t(k) + 1] = t.o0[1] + t.J[1][0] * dx + t.J[1][1] * dy;
    }
  }
  DisjointSets sets(n);
  std::map<std::pair<int64_t, int64_t>, uint32_t> corner;  // old corner (1/1024 texel) -> first triangle
  for (size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      const std::pair<int64_t, int64_t> key{std::llround(old[i][2 * size_t(k)] * 1024), std::llround(old[i][2 * size_t(k) + 1] * 1024)};
      auto [it, fresh] = corner.emplace(key, uint32_t(i));
      if (!fresh) sets.unite(it->second, uint32_t(i));
    }
  sc.chart_of_triangle.resize(n);
  for (size_t i = 0; i < n; ++i) sc.chart_of_triangle[i] = int32_t(sets.find(uint32_t(i)));
  sc.texel.assign(size_t(SW) * SH, kNone);
  for (size_t i = 0; i < n; ++i) {
    const double* a = &old[i][0];
    const double* b = &old[i][2];
    const double* c = &old[i][4];
    const double area = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
    if (area == 0) continue;
    const int x0 = std::max(0, int(std::floor(std::min({a[0], b[0], c[0]})))), x1 = std::min(SW - 1, int(std::ceil(std::max({a[0], b[0], c[0]}))));
    const int y0 = std::max(0, int(std::floor(std::min({a[1], b[1], c[1]})))), y1 = std::min(SH - 1, int(std::ceil(std::max({a[1], b[1], c[1]}))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        const double w0 = (b[0] - px) * (c[1] - py) - (c[0] - px) * (b[1] - py);
        const double w1 = (c[0] - px) * (a[1] - py) - (a[0] - px) * (c[1] - py);
        const double w2 = (a[0] - px) * (b[1] - py) - (b[0] - px) * (a[1] - py);
        const bool inside = area > 0 ? (w0 >= 0 && w1 >= 0 && w2 >= 0) : (w0 <= 0 && w1 <= 0 && w2 <= 0);
        if (!inside) continue;
        int32_t& l = sc.texel[size_t(y) * SW + x];
        if (l == kNone) l = sc.chart_of_triangle[i];
        else if (l != sc.chart_of_triangle[i]) l = kShared;
      }
  }
  return sc;
}

// `owner` extended by `r` texels past the owned ones (Chebyshev distance): pass after pass,
// an unowned texel takes the owner of its first owned 8-neighbour of the previous pass, in
// a fixed neighbour order, so the result does not depend on threads.
std::vector<uint32_t> extend_owners(const std::vector<uint32_t>& owner, int W, int H, uint32_t r) {
  std::vector<uint32_t> cur = owner, next = owner;
  for (uint32_t pass = 0; pass < r; ++pass) {
#pragma omp parallel for schedule(static)
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        if (cur[size_t(y) * W + x] != engine::kRebakeNoOwner) continue;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int u = x + dx, v = y + dy;
            if (u < 0 || v < 0 || u >= W || v >= H) continue;
            const uint32_t o = cur[size_t(v) * W + u];
            if (o != engine::kRebakeNoOwner && next[size_t(y) * W + x] == engine::kRebakeNoOwner) next[size_t(y) * W + x] = o;
          }
      }
    cur = next;
  }
  return cur;
}

}  // namespace

namespace {

// What a triangle's texels share: the kernel's frame M = V min(S^-1, 1) U^T from the SVD
// of its map J = U S V^T and the support's radius in source texels. ok: the map is neither
// degenerate nor squeezed past kMaxShrink.
struct TriangleKernel {
  bool ok = false;
  double M[2][2] = {{0, 0}, {0, 0}};
  double radius = 0;
};

std::vector<TriangleKernel> triangle_kernels(const RebakePlan& plan) {
  std::vector<TriangleKernel> kernels(plan.triangles.size());
  for (size_t i = 0; i < kernels.size(); ++i) {
    const engine::RebakeTriangle& t = plan.triangles[i];
    TriangleKernel& K = kernels[i];
    // SVD of the 2x2 J through its polar-like decomposition: J^T J = V S^2 V^T.
    const double a = t.J[0][0], b = t.J[0][1], c = t.J[1][0], d = t.J[1][1];
    const double p = a * a + c * c, q = a * b + c * d, r = b * b + d * d;
    const double mean = 0.5 * (p + r), dev = std::sqrt(std::max(0.0, 0.25 * (p - r) * (p - r) + q * q));
    const double s1 = std::sqrt(mean + dev), s2 = std::sqrt(std::max(0.0, mean - dev));
    const double theta = 0.5 * std::atan2(2 * q, p - r);  // V's first column angle
    const double v1[2] = {std::cos(theta), std::sin(theta)}, v2[2] = {-v1[1], v1[0]};
    if (!(s2 > 1e-12) || s1 > kMaxShrink) continue;
    // U columns: J v / s; M = sum_k v_k min(1/s_k, 1) u_k^T.
    const double sk[2] = {s1, s2};
    const double* vk[2] = {v1, v2};
    auto& M = K.M;
    for (int k = 0; k < 2; ++k) {
      const double u[2] = {(a * vk[k][0] + b * vk[k][1]) / sk[k], (c * vk[k][0] + d * vk[k][1]) / sk[k]};
      const double f = std::min(1.0 / sk[k], 1.0);
      for (int i2 = 0; i2 < 2; ++i2)
        for (int j = 0; j < 2; ++j) M[i2][j] += vk[k][i2] * f * u[j];
    }
    K.ok = true;
    K.radius = 3 * std::max(s1, 1.0) + 1;
  }
  return kernels;
}

// The Lanczos bake of every texel it can bake, into `out` (the new image's size), whose
// other texels stay as they are. covered: 1 for chart texels and the surround texels
// written. kept: 1 for chart texels not written (they keep the area bake's value).
void lanczos_pass(const Image& source, const RebakePlan& plan, const RebakeOptions& options, Image& out,
                  std::vector<uint8_t>& covered, std::vector<uint8_t>& kept) {
  const int W = plan.width, H = plan.height, C = int(source.channels);
  const int SW = int(source.width), SH = int(source.height);
  covered.assign(size_t(W) * H, 0);
  kept.assign(size_t(W) * H, 0);
  const SourceCharts charts = source_charts(plan, SW, SH);
  const std::vector<uint32_t> owners = options.surround > 0 ? extend_owners(plan.owner, W, H, options.surround) : plan.owner;
  const std::vector<TriangleKernel> kernels = triangle_kernels(plan);
  static const Lanczos3Table kLanczos3;
#pragma omp parallel for schedule(dynamic, 4)
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const uint32_t own = owners[size_t(y) * W + x];
      if (own == engine::kRebakeNoOwner) continue;
      const engine::RebakeTriangle& t = plan.triangles[plan.tile_list[own]];
      const int32_t chart = charts.chart_of_triangle[plan.tile_list[own]];
      // Chart texels count as baked even where the area bake's value stays; surround texels
      // only once this bake writes them (else the gutter fill takes them).
      const bool chart_texel = plan.owner[size_t(y) * W + x] != engine::kRebakeNoOwner;
      if (chart_texel) covered[size_t(y) * W + x] = 1, kept[size_t(y) * W + x] = 1;
      // The texel centre's preimage.
      const double cx = x + 0.5 - t.n[0][0], cy = y + 0.5 - t.n[0][1];
      const double ox = t.o0[0] + t.J[0][0] * cx + t.J[0][1] * cy;
      const double oy = t.o0[1] + t.J[1][0] * cx + t.J[1][1] * cy;
      const TriangleKernel& K = kernels[plan.tile_list[own]];
      if (!K.ok) continue;  // degenerate or squeezed hard: the area bake's value stays (see the header)
      const auto& M = K.M;
      const double radius = K.radius;
      const int x0 = int(std::floor(ox - radius)), x1 = int(std::ceil(ox + radius));
      const int y0 = int(std::floor(oy - radius)), y1 = int(std::ceil(oy + radius));
      double acc[4] = {0, 0, 0, 0}, wsum = 0;
      // Kernel coordinates (kx, ky) = M d, d = tap - preimage: +M(.,0) per column, +M(.,1)
      // per row; per row only the span of columns inside the kernel's square is visited.
      const double dx0 = x0 + 0.5 - ox, dy0 = y0 + 0.5 - oy;
      const bool inside_x = x0 >= 0 && x1 < SW;  // no column wraps
      for (int sy = y0; sy <= y1; ++sy) {
        const double dy = dy0 + (sy - y0);
        const double ax = M[0][0] * dx0 + M[0][1] * dy, ay = M[1][0] * dx0 + M[1][1] * dy;
        int lo = 0, hi = x1 - x0 + 1;
        kernel_span(ax, M[0][0], lo, hi);
        kernel_span(ay, M[1][0], lo, hi);
        if (lo >= hi) continue;
        const size_t row = size_t(engine::rebake_wrap(sy, SH, options.wrap_t)) * SW;
        for (int i = lo; i < hi; ++i) {
          const double kx = ax + M[0][0] * i, ky = ay + M[1][0] * i;
          if (std::abs(kx) >= 3 || std::abs(ky) >= 3) continue;
          const int sx = x0 + i;
          const size_t at = row + size_t(inside_x ? sx : engine::rebake_wrap(sx, SW, options.wrap_s));
          const int32_t label = charts.texel[at];
          if (label != kNone && label != kShared && label != chart) continue;  // another chart's texel
          const double w = kLanczos3(kx) * kLanczos3(ky);
          const float* s = &source.pixels[at * C];
          for (int ch = 0; ch < C; ++ch) acc[ch] += w * s[ch];
          wsum += w;
        }
      }
      if (!(wsum > 1e-6)) continue;
      float* o = &out.pixels[(size_t(y) * W + x) * C];
      for (int ch = 0; ch < C; ++ch) o[ch] = float(std::clamp(acc[ch] / wsum, 0.0, 1.0));
      covered[size_t(y) * W + x] = 1, kept[size_t(y) * W + x] = 0;
    }
}

RebakePlan stored_plan(const Image& source, const std::vector<RebakeMesh>& meshes, const RebakeOptions& options) {
  RebakeOptions stored = options;
  stored.role = RebakeRole::Data;  // the plan's geometry only: values are read as stored
  return plan_rebake(source, meshes, stored);
}

}  // namespace

Image rebake_lanczos(const Image& source, const std::vector<RebakeMesh>& meshes, const RebakeOptions& options,
                     const Image& area, std::vector<uint8_t>* baked) {
  if (options.role == RebakeRole::Normal) return area;
  const RebakePlan plan = stored_plan(source, meshes, options);
  Image out = area;
  std::vector<uint8_t> covered, kept;
  lanczos_pass(source, plan, options, out, covered, kept);
  if (options.fill_gutter) fill_gutter(out, covered, options.role == RebakeRole::Color, fill_ring(options));
  if (baked) {
    baked->resize(covered.size(), 0);
    for (size_t i = 0; i < covered.size(); ++i) (*baked)[i] |= covered[i];
  }
  return out;
}

Image rebake_lanczos(const Image& source, const std::vector<RebakeMesh>& meshes, const RebakeOptions& options,
                     engine::Engine& engine, RebakeStats* stats) {
  // Normal maps are the area bake; without the gutter fill, gutters keep its values too.
  if (options.role == RebakeRole::Normal || !options.fill_gutter) {
    const Image area = rebake(source, meshes, options, engine, stats);
    return rebake_lanczos(source, meshes, options, area, stats ? &stats->coverage : nullptr);
  }
  const RebakePlan plan = stored_plan(source, meshes, options);
  Image out;
  out.width = options.width, out.height = options.height, out.channels = source.channels, out.bits = source.bits;
  out.pixels.assign(size_t(plan.width) * plan.height * source.channels, 0.0f);
  std::vector<uint8_t> covered, kept;
  lanczos_pass(source, plan, options, out, covered, kept);
  // The area bake of the texels the Lanczos pass left (squeezed or degenerate maps; the
  // engine is not called when there are none): the values the area bake made first for
  // every texel would have given them.
  RebakeOptions area_options = options;
  area_options.fill_gutter = false;
  RebakeStats area_stats;
  const Image area = rebake(source, meshes, area_options, engine, &area_stats, &kept);
  const size_t C = source.channels;
  for (size_t i = 0; i < kept.size(); ++i)
    if (kept[i]) std::copy_n(&area.pixels[i * C], C, &out.pixels[i * C]);
  fill_gutter(out, covered, options.role == RebakeRole::Color, fill_ring(options));
  if (stats) {
    *stats = std::move(area_stats);
    for (size_t i = 0; i < covered.size(); ++i) stats->coverage[i] |= covered[i];
  }
  return out;
}

}  // namespace uvpress::atlas
