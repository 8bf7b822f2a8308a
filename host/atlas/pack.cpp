#include "atlas/pack.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>

namespace uvpress::atlas {

bool triangle_overlaps_box(const double a[2], const double b[2], const double c[2], double x0, double y0, double x1,
                           double y1, double eps) {
  // Separating axes: the box's two axes and the triangle's three edge normals. "Overlap"
  // means a positive-area intersection, so touching counts as separated (with a tolerance,
  // so that a chart edge lying exactly on a texel line claims one side only).
  if (std::max({a[0], b[0], c[0]}) <= x0 + eps || std::min({a[0], b[0], c[0]}) >= x1 - eps) return false;
  if (std::max({a[1], b[1], c[1]}) <= y0 + eps || std::min({a[1], b[1], c[1]}) >= y1 - eps) return false;
  const double area2 = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
  if (area2 == 0) return false;
  const double sign = area2 > 0 ? 1.0 : -1.0;
  const double* v[3] = {a, b, c};
  for (int e = 0; e < 3; ++e) {
    const double* p = v[e];
    const double* q = v[(e + 1) % 3];
    // Inward normal (for a counter-clockwise triangle in x-right/y-up terms, sign +).
    const double nx = -(q[1] - p[1]) * sign, ny = (q[0] - p[0]) * sign;
    // The box corner farthest along the inward normal.
    const double bx = nx > 0 ? x1 : x0, by = ny > 0 ? y1 : y0;
    const double scale = std::abs(nx) + std::abs(ny);
    if (nx * (bx - p[0]) + ny * (by - p[1]) <= eps * scale) return false;
  }
  return true;
}

std::array<double, 2> Packing::map(size_t chart, double x, double y) const {
  const ChartPlacement& p = placements[chart];
  const double sx = scale * x, sy = scale * y;
  if (p.rotation == 0) return {sx + p.tx, sy + p.ty};
  return {-sy + p.tx, sx + p.ty};
}

std::array<double, 2> Packing::map_uv(size_t chart, double x, double y) const {
  auto q = map(chart, x, y);
  return {q[0] / width, q[1] / height};
}

namespace {

// A chart's footprint on the packing grid (cells of block x block texels), in its own
// frame: the minimum corner of the scaled chart at the origin.
struct Footprint {
  uint32_t w = 1, h = 1;       // cells
  std::vector<uint8_t> cells;  // h rows of w
  double min_x = 0, min_y = 0; // texels: the scaled chart's minimum corner
  double area = 0;             // scaled triangle area, texels^2
  uint32_t count = 0;          // set cells
};

Footprint rasterize(const ChartShape& chart, double scale, uint32_t block) {
  Footprint f;
  const size_t n = chart.points.size() / 2;
  double mx = std::numeric_limits<double>::infinity(), my = mx, Mx = -mx, My = -mx;
  for (uint32_t i : chart.triangles) {
    if (i >= n) continue;
    mx = std::min(mx, scale * chart.points[2 * i]);
    Mx = std::max(Mx, scale * chart.points[2 * i]);
    my = std::min(my, scale * chart.points[2 * i + 1]);
    My = std::max(My, scale * chart.points[2 * i + 1]);
  }
  if (!(mx <= Mx)) {  // no triangles: one cell
    f.cells.assign(1, 1);
    f.count = 1;
    return f;
  }
  if (chart.snap) mx = std::floor(mx), my = std::floor(my);
  f.min_x = mx, f.min_y = my;
  const double inv = 1.0 / block;
  f.w = std::max<uint32_t>(1, uint32_t(std::ceil((Mx - mx) * inv - 1e-9)));
  f.h = std::max<uint32_t>(1, uint32_t(std::ceil((My - my) * inv - 1e-9)));
  f.cells.assign(size_t(f.w) * f.h, 0);
  for (size_t t = 0; t + 2 < chart.triangles.size(); t += 3) {
    double v[3][2];
    bool bad = false;
    for (int k = 0; k < 3; ++k) {
      const uint32_t i = chart.triangles[t + k];
      if (i >= n) {
        bad = true;
        break;
      }
      v[k][0] = (scale * chart.points[2 * i] - mx) * inv;
      v[k][1] = (scale * chart.points[2 * i + 1] - my) * inv;
    }
    if (bad) continue;
    const double area2 = (v[1][0] - v[0][0]) * (v[2][1] - v[0][1]) - (v[1][1] - v[0][1]) * (v[2][0] - v[0][0]);
    f.area += 0.5 * std::abs(area2) * block * block;
    const double lox = std::min({v[0][0], v[1][0], v[2][0]}), hix = std::max({v[0][0], v[1][0], v[2][0]});
    const double loy = std::min({v[0][1], v[1][1], v[2][1]}), hiy = std::max({v[0][1], v[1][1], v[2][1]});
    const int x0 = std::max(0, int(std::floor(lox))), x1 = std::min(int(f.w) - 1, int(std::ceil(hix)));
    const int y0 = std::max(0, int(std::floor(loy))), y1 = std::min(int(f.h) - 1, int(std::ceil(hiy)));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        uint8_t& c = f.cells[size_t(y) * f.w + x];
        if (!c && triangle_overlaps_box(v[0], v[1], v[2], x, y, x + 1, y + 1)) c = 1;
      }
  }
  for (uint8_t c : f.cells) f.count += c;
  if (f.count == 0) {  // only degenerate triangles
    f.cells[0] = 1;
    f.count = 1;
  }
  return f;
}

// One orientation of a footprint as column profiles. Cell columns/rows of the footprint F
// and of D, F dilated by g cells (D column c = F column c - g; D row r = F row r - g).
struct Profile {
  uint32_t fw = 0, fh = 0;        // F size in cells
  std::vector<int32_t> fbot;      // per F column: last set row, -1 if empty
  std::vector<int32_t> dtop;      // per D column (fw + 2g): first row of D, INT32_MAX if empty
  int32_t dh = 0;                 // D height: fh + 2g
};

Profile profile_of(const Footprint& f, bool rotated, uint32_t g) {
  Profile p;
  p.fw = rotated ? f.h : f.w;
  p.fh = rotated ? f.w : f.h;
  auto cell = [&](uint32_t x, uint32_t y) -> bool {
    // Rotated cell (x, y) is original cell (y, h - 1 - x).
    return rotated ? f.cells[size_t(f.h - 1 - x) * f.w + y] != 0 : f.cells[size_t(y) * f.w + x] != 0;
  };
  std::vector<int32_t> ftop(p.fw, INT32_MAX);
  p.fbot.assign(p.fw, -1);
  for (uint32_t x = 0; x < p.fw; ++x)
    for (uint32_t y = 0; y < p.fh; ++y)
      if (cell(x, y)) {
        ftop[x] = std::min<int32_t>(ftop[x], y);
        p.fbot[x] = y;
      }
  const uint32_t dw = p.fw + 2 * g;
  p.dtop.assign(dw, INT32_MAX);
  for (uint32_t c = 0; c < dw; ++c) {
    const int lo = std::max(0, int(c) - int(2 * g)), hi = std::min(int(p.fw) - 1, int(c));
    for (int j = lo; j <= hi; ++j) p.dtop[c] = std::min(p.dtop[c], ftop[j]);
  }
  p.dh = int32_t(p.fh + 2 * g);
  return p;
}

struct Candidate {
  int64_t cost = std::numeric_limits<int64_t>::max();
  int32_t y = 0, x = 0;
  uint32_t k = 0;
  bool operator<(const Candidate& o) const {
    if (cost != o.cost) return cost < o.cost;
    if (y != o.y) return y < o.y;
    if (x != o.x) return x < o.x;
    return k < o.k;
  }
};

}  // namespace

Packing pack_charts(const std::vector<ChartShape>& charts, uint32_t width, uint32_t height, double scale,
                    const PackOptions& options) {
  Packing out;
  out.width = width, out.height = height, out.scale = scale;
  out.placements.resize(charts.size());
  const uint32_t b = std::max<uint32_t>(1, options.block);
  const uint32_t g = (options.gutter + b - 1) / b;  // gutter in cells
  const int32_t wc = int32_t(width / b), hc = int32_t(height / b);
  if (wc <= 0 || hc <= 0 || !(scale > 0)) return out;

  std::vector<Footprint> prints(charts.size());
  for (size_t i = 0; i < charts.size(); ++i) {
    prints[i] = rasterize(charts[i], scale, b);
    out.chart_area += prints[i].area;
  }
  // Big charts first: by set cells, then by longer side, then input order.
  std::vector<size_t> order(charts.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::sort(order.begin(), order.end(), [&](size_t a, size_t c) {
    if (prints[a].count != prints[c].count) return prints[a].count > prints[c].count;
    const uint32_t la = std::max(prints[a].w, prints[a].h), lc = std::max(prints[c].w, prints[c].h);
    if (la != lc) return la > lc;
    return a < c;
  });

  std::vector<int32_t> horizon(wc, 0);  // first free row per column (below every footprint)
  int32_t top = 0;                      // rows used, gutters included
  for (size_t i : order) {
    const Footprint& f = prints[i];
    Candidate best;
    Profile profiles[2];
    const int orientations = options.rotate ? 2 : 1;
    for (int k = 0; k < orientations; ++k) {
      const Profile& p = profiles[k] = profile_of(f, k == 1, g);
      const int32_t dw = int32_t(p.dtop.size());
      if (dw > wc || p.dh > hc) continue;
      const int32_t nx = wc - dw + 1;
      // Serial scan (a parallel region per chart costs more than it saves): a candidate is
      // pruned as soon as a lower bound of its cost exceeds the best so far (exact: ties are
      // still evaluated, and the order (cost, y, x, k) is total).
      for (int32_t x = 0; x < nx; ++x) {
        Candidate& lb = best;
        const int64_t limit = lb.cost;
        int32_t y = 0;
        bool pruned = false;
        for (int32_t c = 0; c < dw; ++c) {
          if (p.dtop[c] == INT32_MAX) continue;
          y = std::max(y, horizon[x + c] - p.dtop[c]);
          if (y + p.dh > hc || int64_t(std::max(0, y + p.dh - top)) * wc > limit) {
            pruned = true;
            break;
          }
        }
        if (pruned) continue;
        int64_t cost = int64_t(std::max(0, y + p.dh - top)) * wc;
        for (int32_t c = 0; c < dw && cost <= limit; ++c)
          if (p.dtop[c] != INT32_MAX) cost += y + p.dtop[c] - horizon[x + c];
        if (cost > limit) continue;
        Candidate cand{cost, y, x, uint32_t(k)};
        if (cand < lb) lb = cand;
      }
    }
    if (best.cost == std::numeric_limits<int64_t>::max()) return out;  // does not fit
    const Profile& p = profiles[best.k];
    for (uint32_t j = 0; j < p.fw; ++j)
      if (p.fbot[j] >= 0) {
        int32_t& h = horizon[best.x + g + j];
        h = std::max(h, best.y + int32_t(g) + p.fbot[j] + 1);
      }
    top = std::max(top, best.y + p.dh);
    // Footprint origin in texels, and the affine placement.
    ChartPlacement& pl = out.placements[i];
    pl.rotation = best.k;
    pl.x = (best.x + g) * b;
    pl.y = (best.y + g) * b;
    pl.width = p.fw * b;
    pl.height = p.fh * b;
    if (best.k == 0) {
      pl.tx = pl.x - f.min_x;
      pl.ty = pl.y - f.min_y;
    } else {  // atlas = O + R1 (s p - m) + (b h, 0), R1 (x, y) = (-y, x)
      pl.tx = pl.x + f.min_y + double(f.h) * b;
      pl.ty = pl.y - f.min_x;
    }
  }
  out.ok = true;
  out.used_height = uint32_t(top) * b;
  out.efficiency = out.chart_area / (double(width) * height);
  return out;
}

namespace {

// Sum of |triangle areas| of all charts at scale 1 (out-of-range indices skipped).
double chart_area(const std::vector<ChartShape>& charts) {
  double area = 0;
  for (const auto& c : charts) {
    const size_t n = c.points.size() / 2;
    for (size_t t = 0; t + 2 < c.triangles.size(); t += 3) {
      const uint32_t i = c.triangles[t], j = c.triangles[t + 1], k = c.triangles[t + 2];
      if (i >= n || j >= n || k >= n) continue;
      const double* a = &c.points[2 * i];
      const double* b = &c.points[2 * j];
      const double* d = &c.points[2 * k];
      area += 0.5 * std::abs((b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0]));
    }
  }
  return area;
}

}  // namespace

Packing pack_max_scale(const std::vector<ChartShape>& charts, uint32_t width, uint32_t height,
                       const PackOptions& options, double s_max, double tolerance) {
  const double area1 = chart_area(charts);  // at scale 1
  double hi = s_max;
  if (area1 > 0) hi = std::min(hi, std::sqrt(double(width) * height / area1));
  Packing best = pack_charts(charts, width, height, hi, options);
  if (best.ok) return best;
  double fail = hi, lo = hi;
  for (;;) {  // find a scale that fits
    lo *= 0.5;
    if (lo < 1e-6) return best;  // ok = false
    Packing p = pack_charts(charts, width, height, lo, options);
    if (p.ok) {
      best = std::move(p);
      break;
    }
    fail = lo;
  }
  while (fail > lo * (1 + tolerance)) {
    const double mid = std::sqrt(lo * fail);
    Packing p = pack_charts(charts, width, height, mid, options);
    if (p.ok) {
      best = std::move(p);
      lo = mid;
    } else {
      fail = mid;
    }
  }
  return best;
}

namespace {

struct SizeRule {
  double aspect = 1;  // width / height
  bool pot = false;
  uint32_t block = 1;

  static uint32_t round_up(uint32_t v, uint32_t b) { return std::max(b, (v + b - 1) / b * b); }

  // Longer side L (a power of two when pot) -> width, height.
  std::array<uint32_t, 2> dims(uint32_t L) const {
    uint32_t other;
    const double r = aspect >= 1 ? aspect : 1 / aspect;
    if (pot) {
      const int e = int(std::lround(std::log2(r)));
      other = std::max<uint32_t>(1, L >> std::min(e, 31));
    } else {
      other = std::max<uint32_t>(1, uint32_t(std::lround(L / r)));
    }
    uint32_t w = aspect >= 1 ? L : other, h = aspect >= 1 ? other : L;
    return {round_up(w, block), round_up(h, block)};
  }
  uint32_t nearest_pot(double L) const {
    const int e = std::clamp(int(std::lround(std::log2(std::max(1.0, L)))), 0, 30);
    return 1u << e;
  }
};

constexpr uint32_t kMaxSide = 1u << 16;

}  // namespace

AtlasChoice choose_atlas(const std::vector<ChartShape>& charts, uint32_t old_width, uint32_t old_height,
                         double old_used_texels, const BudgetOptions& o) {
  AtlasChoice choice;
  SizeRule rule;
  rule.aspect = o.keep_aspect && old_width > 0 && old_height > 0 ? double(old_width) / old_height : 1.0;
  rule.pot = o.pot;
  rule.block = std::max<uint32_t>(1, o.pack.block);
  const double r = rule.aspect >= 1 ? rule.aspect : 1 / rule.aspect;

  const double area1 = chart_area(charts);

  auto fits_at = [&](uint32_t L, double s) {
    auto d = rule.dims(L);
    return pack_charts(charts, d[0], d[1], s, o.pack);
  };
  // Smallest longer side (non-pot) holding the charts at scale s; 0 if none <= kMaxSide.
  auto smallest_side = [&](double s) -> uint32_t {
    uint32_t lo = std::max<uint32_t>(1, uint32_t(std::sqrt(s * s * area1 * r)));  // area bound
    if (lo > 1) --lo;
    uint32_t hi = std::max<uint32_t>(lo + 1, 2);
    while (!fits_at(hi, s).ok) {
      lo = hi;
      if (hi >= kMaxSide) return 0;
      hi = std::min(kMaxSide, hi * 2);
    }
    while (hi - lo > 1) {  // lo: not known to fit, hi fits
      const uint32_t mid = lo + (hi - lo) / 2;
      if (fits_at(mid, s).ok)
        hi = mid;
      else
        lo = mid;
    }
    return hi;
  };

  Packing p;
  if (o.size > 0) {
    const uint32_t L = o.pot ? rule.nearest_pot(o.size) : o.size;
    auto d = rule.dims(L);
    p = pack_max_scale(charts, d[0], d[1], o.pack, o.s_max);
  } else if (o.measure == CostMeasure::ChartTexels && old_used_texels > 0 && area1 > 0) {
    const double s = std::min(o.s_max, std::sqrt(o.cost * old_used_texels / area1));
    const uint32_t L = smallest_side(s);
    if (L == 0) return choice;
    if (o.pot) {
      auto d = rule.dims(rule.nearest_pot(L));
      p = pack_max_scale(charts, d[0], d[1], o.pack, o.s_max);
    } else {
      p = fits_at(L, s);
    }
  } else {
    const double texels = o.cost * double(old_width) * old_height;
    const double Lf = std::sqrt(texels * r);
    uint32_t L = o.pot ? rule.nearest_pot(Lf) : std::max<uint32_t>(1, uint32_t(std::lround(Lf)));
    auto d = rule.dims(L);
    p = pack_max_scale(charts, d[0], d[1], o.pack, o.s_max);
    if (p.ok && p.scale >= o.s_max) {  // at full density: shrink the atlas to what is needed
      if (o.pot) {
        while (L > 1) {
          Packing q = fits_at(L / 2, o.s_max);
          if (!q.ok) break;
          p = std::move(q);
          L /= 2;
        }
      } else {
        const uint32_t Ls = smallest_side(o.s_max);
        if (Ls > 0 && Ls < L) p = fits_at(Ls, o.s_max);
      }
    }
  }
  if (!p.ok) return choice;
  choice.packing = std::move(p);
  const Packing& q = choice.packing;
  if (old_used_texels > 0) choice.cost_ratio = q.chart_area / old_used_texels;
  if (old_width > 0 && old_height > 0) choice.texel_ratio = double(q.width) * q.height / (double(old_width) * old_height);
  return choice;
}

}  // namespace uvpress::atlas
