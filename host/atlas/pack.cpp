#include "atlas/pack.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
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
  const double sx = p.scale * x, sy = p.scale * y;
  switch (p.rotation) {
    case 0: return {sx + p.tx, sy + p.ty};
    case 1: return {-sy + p.tx, sx + p.ty};
    case 2: return {-sx + p.tx, -sy + p.ty};
    default: return {sy + p.tx, -sx + p.ty};
  }
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
  uint64_t covered = 0;        // texels whose centre some triangle covers (overlaps once)
  uint32_t stride = 1;         // cells: positions are multiples of it (ChartShape::align)
  double scale = 1;            // the chart's scale: the packing's, or 1 when pinned
};

// The x-extent of triangle v cut to the band y0 <= y <= y1 (y0 == y1: a line): its
// vertices inside the band and its edges' crossings of the band's two lines. False when
// the triangle misses the band.
bool x_extent(const double v[3][2], double y0, double y1, double& xl, double& xr) {
  xl = std::numeric_limits<double>::infinity(), xr = -xl;
  for (int k = 0; k < 3; ++k) {
    const double* p = v[k];
    const double* q = v[(k + 1) % 3];
    if (p[1] >= y0 && p[1] <= y1) xl = std::min(xl, p[0]), xr = std::max(xr, p[0]);
    for (const double line : {y0, y1})
      if ((p[1] - line) * (q[1] - line) < 0) {
        const double x = p[0] + (q[0] - p[0]) * (line - p[1]) / (q[1] - p[1]);
        xl = std::min(xl, x), xr = std::max(xr, x);
      }
  }
  return xl <= xr;
}

// Texel centres (x + 1/2, y + 1/2) inside triangle v (texel units), marked in `mask`
// (width x height texels): per texel row, the centres between the two edge crossings.
void mark_centres(const double v[3][2], uint32_t width, uint32_t height, std::vector<uint8_t>& mask) {
  const double lo = std::min({v[0][1], v[1][1], v[2][1]}), hi = std::max({v[0][1], v[1][1], v[2][1]});
  const int j0 = std::max(0, int(std::ceil(lo - 0.5))), j1 = std::min(int(height) - 1, int(std::floor(hi - 0.5)));
  for (int j = j0; j <= j1; ++j) {
    double xl, xr;
    if (!x_extent(v, j + 0.5, j + 0.5, xl, xr)) continue;
    const int i0 = std::max(0, int(std::ceil(xl - 0.5))), i1 = std::min(int(width) - 1, int(std::floor(xr - 0.5)));
    for (int i = i0; i <= i1; ++i) mask[size_t(j) * width + size_t(i)] = 1;
  }
}

Footprint rasterize(const ChartShape& chart, double scale, uint32_t block) {
  Footprint f;
  if (chart.pinned) scale = 1;
  f.scale = scale;
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
  // Aligned: the origin on a multiple of align, the extent padded to one (empty cells), so
  // that every quarter turn's translation (place) is a multiple of align as well.
  const bool aligned = chart.snap && chart.align > 1 && chart.align % block == 0;
  const double a = aligned ? chart.align : 1;
  if (chart.snap) mx = std::floor(mx / a) * a, my = std::floor(my / a) * a;
  f.min_x = mx, f.min_y = my;
  const double inv = 1.0 / block;
  f.stride = aligned ? chart.align / block : 1;
  auto cells = [&](double extent) {
    const uint32_t c = std::max<uint32_t>(1, uint32_t(std::ceil(extent * inv - 1e-9)));
    return (c + f.stride - 1) / f.stride * f.stride;
  };
  f.w = cells(Mx - mx), f.h = cells(My - my);
  f.cells.assign(size_t(f.w) * f.h, 0);
  std::vector<uint8_t> centres(size_t(f.w) * block * f.h * block, 0);
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
    if (area2 != 0) {
      const double vt[3][2] = {{v[0][0] * block, v[0][1] * block}, {v[1][0] * block, v[1][1] * block}, {v[2][0] * block, v[2][1] * block}};
      mark_centres(vt, f.w * block, f.h * block, centres);
    }
    const double lox = std::min({v[0][0], v[1][0], v[2][0]}), hix = std::max({v[0][0], v[1][0], v[2][0]});
    const double loy = std::min({v[0][1], v[1][1], v[2][1]}), hiy = std::max({v[0][1], v[1][1], v[2][1]});
    const int x0 = std::max(0, int(std::floor(lox))), x1 = std::min(int(f.w) - 1, int(std::ceil(hix)));
    const int y0 = std::max(0, int(std::floor(loy))), y1 = std::min(int(f.h) - 1, int(std::ceil(hiy)));
    // Per row, the cells a triangle overlaps are one run (the triangle cut to the row's slab
    // is convex): the exact test finds its two ends, the cells between are filled.
    for (int y = y0; y <= y1; ++y) {
      double sl, sr;  // the extent in the row's slab; the exact test then settles the end cells
      if (!x_extent(v, y, y + 1, sl, sr)) continue;
      int a = std::max(x0, int(std::floor(sl)) - 1), e = std::min(x1, int(std::ceil(sr)));
      while (a <= e && !triangle_overlaps_box(v[0], v[1], v[2], a, y, a + 1, y + 1)) ++a;
      while (e > a && !triangle_overlaps_box(v[0], v[1], v[2], e, y, e + 1, y + 1)) --e;
      if (a <= e) std::fill(f.cells.begin() + ptrdiff_t(size_t(y) * f.w + size_t(a)), f.cells.begin() + ptrdiff_t(size_t(y) * f.w + size_t(e) + 1), uint8_t(1));
    }
  }
  for (uint8_t c : f.cells) f.count += c;
  for (uint8_t c : centres) f.covered += c;
  if (f.count == 0) {  // only degenerate triangles
    f.cells[0] = 1;
    f.count = 1;
  }
  return f;
}

// Cells that a new footprint cell may not take: within the gutter of a placed footprint
// (Chebyshev distance <= g cells) or of the image edge. One bit per cell, rows of 64-bit
// words, so that a footprint row is tested against a run of cells a word at a time.
class Blocked {
 public:
  Blocked(int32_t w, int32_t h) : w_(w), h_(h), words_((size_t(w) + 63) / 64), bits_(words_ * size_t(h), 0) {}

  // Sets cells [a, b] of row y (clipped to the atlas).
  void set(int32_t y, int32_t a, int32_t b) {
    if (y < 0 || y >= h_) return;
    a = std::max(a, 0), b = std::min(b, w_ - 1);
    if (a > b) return;
    uint64_t* row = &bits_[size_t(y) * words_];
    const int32_t wa = a >> 6, wb = b >> 6;
    for (int32_t k = wa; k <= wb; ++k) {
      const int32_t lo = k == wa ? a & 63 : 0, hi = k == wb ? b & 63 : 63;
      row[k] |= (hi == 63 ? ~uint64_t(0) : (uint64_t(1) << (hi + 1)) - 1) & ~((uint64_t(1) << lo) - 1);
    }
  }

  // The first blocked (or, with free, unblocked) cell of row y in [a, b] (inside the
  // atlas), or -1.
  int32_t first(int32_t y, int32_t a, int32_t b, bool free = false) const {
    const uint64_t* row = &bits_[size_t(y) * words_];
    const int32_t wa = a >> 6, wb = b >> 6;
    for (int32_t k = wa; k <= wb; ++k) {
      uint64_t m = free ? ~row[k] : row[k];
      if (k == wa) m &= ~((uint64_t(1) << (a & 63)) - 1);
      if (k == wb && (b & 63) != 63) m &= (uint64_t(1) << ((b & 63) + 1)) - 1;
      if (m) return (k << 6) + __builtin_ctzll(m);
    }
    return -1;
  }

  // The first p >= from with cells [p, p + len) of row y unblocked and inside the atlas,
  // or -1: each blocked cell found moves p past it.
  int32_t next_free_run(int32_t y, int32_t from, int32_t len) const {
    for (int32_t p = from; p + len <= w_;) {
      p = first(y, p, w_ - 1, true);
      if (p < 0 || p + len > w_) return -1;
      const int32_t c = first(y, p, p + len - 1);
      if (c < 0) return p;
      p = c + 1;
    }
    return -1;
  }

  // Blocked cells in all.
  uint64_t count() const {
    uint64_t n = 0;
    for (uint64_t word : bits_) n += uint64_t(__builtin_popcountll(word));
    return n;
  }

  // The longest run of unblocked cells in row y.
  int32_t longest_free(int32_t y) const {
    int32_t best = 0;
    for (int32_t x = 0; x < w_;) {
      const int32_t z = first(y, x, w_ - 1, true);
      if (z < 0) break;
      int32_t e = first(y, z, w_ - 1);
      if (e < 0) e = w_;
      best = std::max(best, e - z);
      x = e;
    }
    return best;
  }

 private:
  int32_t w_, h_;
  size_t words_;
  std::vector<uint64_t> bits_;
};

// One orientation of a footprint: its size in cells and its set cells as runs per row.
struct Oriented {
  int32_t fw = 0, fh = 0;
  int32_t stride = 1;  // positions are multiples of it (Footprint::stride)
  struct Run {
    int32_t row, a, b;  // cells [a, b] of row `row` are set
  };
  std::vector<Run> runs;  // in test order (see orient)
  // The rows with the widest runs, and those widths: a row of the atlas whose longest
  // free run is shorter rules out every position that puts such a row there.
  std::array<Run, 3> widest{};
  size_t widest_count = 0;
};

// The runs of set cells along rows (columns = false) or columns of a footprint:
// {line, first, last} with line the row (column) and first..last the columns (rows).
std::vector<Oriented::Run> runs_of(const Footprint& f, bool columns) {
  std::vector<Oriented::Run> runs;
  const int32_t lines = int32_t(columns ? f.w : f.h), len = int32_t(columns ? f.h : f.w);
  auto cell = [&](int32_t line, int32_t i) {
    return (columns ? f.cells[size_t(i) * f.w + size_t(line)] : f.cells[size_t(line) * f.w + size_t(i)]) != 0;
  };
  for (int32_t line = 0; line < lines; ++line)
    for (int32_t i = 0; i < len; ++i) {
      if (!cell(line, i)) continue;
      int32_t e = i;
      while (e + 1 < len && cell(line, e + 1)) ++e;
      runs.push_back({line, i, e});
      i = e;
    }
  return runs;
}

// Orientation k of a footprint from its row and column runs. After k quarter turns
// (R_1 (x, y) = (-y, x)), cell (x, y) is original cell k = 1: (y, h - 1 - x); k = 2:
// (w - 1 - x, h - 1 - y); k = 3: (w - 1 - y, x). So turned rows are original rows (k even)
// or columns (k odd), mirrored where the formula has a minus.
Oriented orient(const Footprint& f, const std::vector<Oriented::Run>& rows, const std::vector<Oriented::Run>& columns,
                uint32_t k) {
  Oriented o;
  o.fw = int32_t(k % 2 ? f.h : f.w);
  o.fh = int32_t(k % 2 ? f.w : f.h);
  o.stride = int32_t(f.stride);
  const int32_t w = int32_t(f.w), h = int32_t(f.h);
  o.runs.reserve(k % 2 ? columns.size() : rows.size());
  switch (k) {
    case 0: o.runs = rows; break;
    case 1: for (const auto& r : columns) o.runs.push_back({r.row, h - 1 - r.b, h - 1 - r.a}); break;
    case 2: for (const auto& r : rows) o.runs.push_back({h - 1 - r.row, w - 1 - r.b, w - 1 - r.a}); break;
    default: for (const auto& r : columns) o.runs.push_back({w - 1 - r.row, r.a, r.b}); break;
  }
  // Test order: rows spread over the footprint (bit-reversed index order) rather than
  // row by row or widest first. A position that fails usually fails at one edge of the
  // footprint; neighbouring rows pass or fail together, so spreading the tests finds the
  // colliding row after a few tests (5-20x fewer on the shared assets' charts). The order
  // changes the speed only: the first free position is the same.
  std::stable_sort(o.runs.begin(), o.runs.end(), [](const Oriented::Run& p, const Oriented::Run& q) { return p.row < q.row; });
  {
    const size_t n = o.runs.size();
    size_t bits = 0;
    while ((size_t(1) << bits) < n) ++bits;
    std::vector<Oriented::Run> spread;
    spread.reserve(n);
    for (size_t i = 0; i < (size_t(1) << bits); ++i) {
      size_t j = 0;
      for (size_t b = 0; b < bits; ++b)
        if ((i >> b) & 1) j |= size_t(1) << (bits - 1 - b);
      if (j < n) spread.push_back(o.runs[j]);
    }
    o.runs = std::move(spread);
  }
  std::vector<Oriented::Run> by_width = o.runs;
  std::stable_sort(by_width.begin(), by_width.end(), [](const Oriented::Run& p, const Oriented::Run& q) { return p.b - p.a > q.b - q.a; });
  for (const Oriented::Run& r : by_width) {
    if (o.widest_count == o.widest.size()) break;
    bool seen = false;
    for (size_t k = 0; k < o.widest_count; ++k) seen |= o.widest[k].row == r.row;
    if (!seen) o.widest[o.widest_count++] = r;
  }
  return o;
}

// The first free position of `o` in reading order (lowest row, then leftmost column), or
// {-1, -1}; both coordinates multiples of o.stride. A position (x, y) is free when no run
// lands on a blocked cell; a run that does rules out every x' <= (blocked cell) - a, so the
// scan jumps past it (a row of the atlas costs a few jumps, not a test per column).
std::array<int32_t, 2> first_fit(const Blocked& blocked, const std::vector<int32_t>& longest, const Oriented& o,
                                 int32_t wc, int32_t hc, int32_t y_end) {
  if (o.fw > wc || o.fh > hc || o.runs.empty()) return {-1, -1};
  const int32_t stride = o.stride;
  for (int32_t y = 0; y + o.fh <= hc && y < y_end; y += stride) {
    bool room = true;
    for (size_t k = 0; k < o.widest_count && room; ++k) room = longest[size_t(y + o.widest[k].row)] > o.widest[k].b - o.widest[k].a;
    if (!room) continue;
    int32_t x = 0;
    size_t hint = 0;  // the run that collided last is tried first
    while (x + o.fw <= wc) {
      bool fits = true;
      for (size_t k = 0; k < o.runs.size(); ++k) {
        const Oriented::Run& r = o.runs[(hint + k) % o.runs.size()];
        if (blocked.first(y + r.row, x + r.a, x + r.b) < 0) continue;
        // Move to where this run fits in its row: no position in between can.
        const int32_t p = blocked.next_free_run(y + r.row, x + r.a, r.b - r.a + 1);
        x = p < 0 ? wc : (p - r.a + stride - 1) / stride * stride;
        hint = (hint + k) % o.runs.size();
        fits = false;
        break;
      }
      if (fits) return {x, y};
    }
  }
  return {-1, -1};
}

// Every chart's footprint at one scale, in its four orientations: rasterized once and
// placed into as many atlas sizes as the search tries.
struct Prints {
  double scale = 1;
  uint32_t block = 1;
  double area = 0;  // sum of scaled triangle areas, texels^2
  double covered = 0;  // texels under the charts
  std::vector<Footprint> prints;
  std::vector<std::array<Oriented, 4>> oriented;
};

Prints rasterize_all(const std::vector<ChartShape>& charts, double scale, const PackOptions& options) {
  Prints p;
  p.scale = scale;
  p.block = std::max<uint32_t>(1, options.block);
  p.prints.resize(charts.size());
  p.oriented.resize(charts.size());
  for (size_t i = 0; i < charts.size(); ++i) {
    p.prints[i] = rasterize(charts[i], scale, p.block);
    p.area += p.prints[i].area;
    p.covered += double(p.prints[i].covered);
    const auto rows = runs_of(p.prints[i], false), columns = options.rotate ? runs_of(p.prints[i], true) : rows;
    for (uint32_t k = 0; k < (options.rotate ? 4u : 1u); ++k) p.oriented[i][k] = orient(p.prints[i], rows, columns, k);
  }
  return p;
}

// How one attempt orders the charts and picks among the orientations' first fits. No one
// rule packs every set of shapes best (measured on the shared assets' charts, the best
// rule differs per asset by up to 8 points of efficiency), and a failed attempt is cheap
// next to the bisections around it, so the packer tries these in turn.
struct Strategy {
  enum class Order { BoxArea, Cells, Height } order;
  enum class Pick { ReadingOrder, LowestBottom } pick;
};
constexpr Strategy kStrategies[] = {
    {Strategy::Order::BoxArea, Strategy::Pick::ReadingOrder},
    {Strategy::Order::Cells, Strategy::Pick::ReadingOrder},
    {Strategy::Order::Height, Strategy::Pick::LowestBottom},
};

// Bottom-left fill of every chart into width x height, biggest first, each at the first
// free position of its best orientation; the occupied cells, dilated by the gutter, are a
// bitmap, so holes under overhangs and between charts stay available to smaller charts.
Packing place(const Prints& P, uint32_t width, uint32_t height, const PackOptions& options, const Strategy& strategy) {
  Packing out;
  const size_t n = P.prints.size();
  out.width = width, out.height = height, out.scale = P.scale;
  out.placements.resize(n);
  out.chart_area = P.area;
  out.covered = P.covered;
  const uint32_t b = P.block;
  const int32_t g = int32_t((options.gutter + b - 1) / b);  // gutter in cells
  const auto edge = [&](uint32_t e) { return int32_t(((e == PackOptions::kEdgeAsGutter ? options.gutter : e) + b - 1) / b); };
  const int32_t ex = edge(options.edge_x), ey = edge(options.edge_y);  // in cells
  const int32_t wc = int32_t(width / b), hc = int32_t(height / b);
  if (wc <= 0 || hc <= 0 || !(P.scale > 0)) return out;

  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t(0));
  auto key = [&](size_t i) -> uint64_t {
    const Footprint& f = P.prints[i];
    switch (strategy.order) {
      case Strategy::Order::BoxArea: return uint64_t(f.w) * f.h;
      case Strategy::Order::Cells: return f.count;
      default: return std::min(f.w, f.h);  // the side that stays vertical in some orientation
    }
  };
  std::sort(order.begin(), order.end(), [&](size_t a, size_t c) {
    const uint64_t ka = key(a), kc = key(c);
    if (ka != kc) return ka > kc;
    if (P.prints[a].count != P.prints[c].count) return P.prints[a].count > P.prints[c].count;
    return a < c;
  });

  Blocked blocked(wc, hc);
  std::vector<int32_t> longest(size_t(hc), 0);
  for (int32_t y = 0; y < hc; ++y) {
    if (y < ey || y >= hc - ey) {
      blocked.set(y, 0, wc - 1);
    } else {
      blocked.set(y, 0, ex - 1);
      blocked.set(y, wc - ex, wc - 1);
    }
    longest[size_t(y)] = blocked.longest_free(y);
  }
  const uint32_t orientations = options.rotate ? 4 : 1;
  for (size_t i : order) {
    const Footprint& f = P.prints[i];
    // Each orientation's first free position in reading order; the orientation kept is the
    // earliest in reading order or the one whose footprint ends highest (ties: fewer
    // turns). A later orientation is searched only down to where it could still win.
    const Oriented* best = nullptr;
    std::array<int32_t, 2> at{-1, -1};
    uint32_t best_k = 0;
    for (uint32_t k = 0; k < orientations; ++k) {
      const Oriented& o = P.oriented[i][k];
      int32_t y_end = hc;
      if (best) y_end = strategy.pick == Strategy::Pick::ReadingOrder ? at[1] + 1 : at[1] + best->fh - o.fh;
      auto p = first_fit(blocked, longest, o, wc, hc, y_end);
      if (p[1] < 0) continue;
      const bool better = !best || (strategy.pick == Strategy::Pick::ReadingOrder
                                        ? std::make_pair(p[1], p[0]) < std::make_pair(at[1], at[0])
                                        : p[1] + o.fh < at[1] + best->fh);
      if (better) at = p, best = &o, best_k = k;
    }
    if (!best) return out;  // does not fit
    for (const Oriented::Run& r : best->runs)
      for (int32_t dy = -g; dy <= g; ++dy) blocked.set(at[1] + r.row + dy, at[0] + r.a - g, at[0] + r.b + g);
    for (int32_t y = std::max(0, at[1] - g); y < std::min(hc, at[1] + best->fh + g); ++y) longest[size_t(y)] = blocked.longest_free(y);
    // Footprint origin in texels, and the affine placement.
    ChartPlacement& pl = out.placements[i];
    pl.rotation = best_k;
    pl.scale = f.scale;
    pl.x = uint32_t(at[0]) * b;
    pl.y = uint32_t(at[1]) * b;
    pl.width = uint32_t(best->fw) * b;
    pl.height = uint32_t(best->fh) * b;
    // atlas = O + R_k (s p - m) + (the turned footprint's shift back into the quadrant),
    // with O the footprint's corner, m the scaled chart's minimum corner, and fw x fh the
    // footprint's extent in texels before turning.
    const double fw = double(f.w) * b, fh = double(f.h) * b;
    switch (best_k) {
      case 0: pl.tx = pl.x - f.min_x, pl.ty = pl.y - f.min_y; break;
      case 1: pl.tx = pl.x + f.min_y + fh, pl.ty = pl.y - f.min_x; break;
      case 2: pl.tx = pl.x + f.min_x + fw, pl.ty = pl.y + f.min_y + fh; break;
      default: pl.tx = pl.x - f.min_y, pl.ty = pl.y + f.min_x + fw; break;
    }
  }
  out.ok = true;
  double footprint_cells = 0;
  for (const Footprint& f : P.prints) footprint_cells += f.count;
  out.gutter_texels = (double(blocked.count()) - footprint_cells) * b * b;
  out.footprint_texels = footprint_cells * b * b;
  out.efficiency = out.covered / (double(width) * height);
  return out;
}

Packing place_any(const Prints& P, uint32_t width, uint32_t height, const PackOptions& options) {
  Packing p;
  for (const Strategy& s : kStrategies) {
    p = place(P, width, height, options, s);
    if (p.ok) break;
  }
  return p;
}

}  // namespace

uint32_t mip_phase_align(uint32_t gutter, uint32_t block) {
  uint32_t a = 1;
  while (2 * a <= gutter) a *= 2;
  block = std::max(1u, block);
  return a % block == 0 ? a : 1;
}

Packing pack_charts(const std::vector<ChartShape>& charts, uint32_t width, uint32_t height, double scale,
                    const PackOptions& options) {
  return place_any(rasterize_all(charts, scale, options), width, height, options);
}

namespace {

// Sum of |triangle areas| of one chart at scale 1 (out-of-range indices skipped).
double chart_area(const ChartShape& c) {
  double area = 0;
  const size_t n = c.points.size() / 2;
  for (size_t t = 0; t + 2 < c.triangles.size(); t += 3) {
    const uint32_t i = c.triangles[t], j = c.triangles[t + 1], k = c.triangles[t + 2];
    if (i >= n || j >= n || k >= n) continue;
    const double* a = &c.points[2 * i];
    const double* b = &c.points[2 * j];
    const double* d = &c.points[2 * k];
    area += 0.5 * std::abs((b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0]));
  }
  return area;
}

// ... of all charts.
double chart_area(const std::vector<ChartShape>& charts) {
  double area = 0;
  for (const auto& c : charts) area += chart_area(c);
  return area;
}

// ... of the pinned charts (ChartShape::pinned), or of the others.
double chart_area(const std::vector<ChartShape>& charts, bool pinned) {
  double area = 0;
  for (const auto& c : charts)
    if (c.pinned == pinned) area += chart_area(c);
  return area;
}

}  // namespace

Packing pack_max_scale(const std::vector<ChartShape>& charts, uint32_t width, uint32_t height,
                       const PackOptions& options, double s_max, double tolerance) {
  // The scale at which the texels under the charts (overlaps once) would fill the image is
  // an upper bound: texel centres counted at a probe scale of at most ~4M texels, with 5 %
  // to spare for the count's discretization. (The sum of triangle areas would be too low a
  // bound where charts share texels.)
  // Pinned charts take their texels at every scale: the bound is the scale at which the
  // others fill what they leave.
  const double area1 = chart_area(charts, false);  // the charts not pinned, at scale 1 (overlaps twice)
  const bool any_pinned = std::any_of(charts.begin(), charts.end(), [](const ChartShape& c) { return c.pinned; });
  if (any_pinned && area1 <= 0) return pack_charts(charts, width, height, s_max, options);  // no scale to choose
  double hi = s_max;
  if (area1 > 0) {
    const double probe = std::min(1.0, std::sqrt(4e6 / area1));
    const Prints p = rasterize_all(charts, probe, options);
    double pinned = 0;
    for (size_t i = 0; i < charts.size(); ++i)
      if (charts[i].pinned) pinned += double(p.prints[i].covered);
    const double covered1 = (p.covered - pinned) / (probe * probe), room = double(width) * height - pinned;
    if (room <= 0) return Packing{};  // the pinned charts alone fill the image
    if (covered1 > 0) hi = std::min(hi, 1.05 * std::sqrt(room / covered1));
  }
  Packing best = pack_charts(charts, width, height, hi, options);
  if (best.ok) return best;
  // Pinned charts that do not fit beside the others at the smallest scale tried below fit
  // at none: said at once, not after the descent's ~60 packings.
  if (any_pinned && !pack_charts(charts, width, height, 1e-6, options).ok) return best;
  double fail = hi, lo = hi;
  for (;;) {  // find a scale that fits: packers rarely reach 80 % of the image, never 100 %
    lo *= 0.8;
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
  uint32_t block = 1;  // sides are multiples of it (side_unit)

  static uint32_t round_up(uint32_t v, uint32_t b) { return std::max(b, (v + b - 1) / b * b); }

  // Longer side L (a power of two when pot) -> width, height. With a budget of `texels`
  // (image texels, without pot), never more than it: the two sides, each rounded on its own,
  // could exceed it by up to a side (the demo at half its texels: 316 x 415 = 0.5003 of the
  // source's), so then one of them gives way (below).
  std::array<uint32_t, 2> dims(uint32_t L, double texels = 0) const {
    const double r = aspect >= 1 ? aspect : 1 / aspect;
    // Longer and shorter side, each rounded up to whole blocks.
    auto sides = [&](uint32_t longer) -> std::array<uint32_t, 2> {
      uint32_t other;
      if (pot) {
        const int e = int(std::lround(std::log2(r)));
        other = std::max<uint32_t>(1, longer >> std::min(e, 31));
      } else {
        other = std::max<uint32_t>(1, uint32_t(std::lround(longer / r)));
      }
      return {round_up(longer, block), round_up(other, block)};
    };
    std::array<uint32_t, 2> d = sides(L);
    if (!pot && texels > 0 && double(d[0]) * d[1] > texels) {
      // Over: the shorter side gives way, or the longer one by a block (a block-rounded
      // square, 91 -> 96 a side, is better 88 x 88 than 96 x 80), whichever keeps more.
      const auto fit = [&](std::array<uint32_t, 2> s) {
        s[1] = std::min(s[1], std::max(block, uint32_t(std::floor(texels / s[0])) / block * block));
        return s;
      };
      const std::array<uint32_t, 2> a = fit(d);
      const std::array<uint32_t, 2> b = d[0] > block ? fit(sides(d[0] - block)) : a;
      d = double(b[0]) * b[1] > double(a[0]) * a[1] ? b : a;
    }
    return aspect >= 1 ? d : std::array<uint32_t, 2>{d[1], d[0]};
  }
  uint32_t nearest_pot(double L) const {
    const int e = std::clamp(int(std::lround(std::log2(std::max(1.0, L)))), 0, 30);
    return 1u << e;
  }
};

constexpr uint32_t kMaxSide = 1u << 16;

// What an atlas's sides are multiples of: the block, or BudgetOptions::side_multiple where
// the block divides it.
uint32_t side_unit(const BudgetOptions& o) {
  const uint32_t block = std::max<uint32_t>(1, o.pack.block);
  return o.side_multiple % block == 0 ? std::max(o.side_multiple, block) : block;
}

// The longer side of an atlas of `texels` image texels whose sides are r : 1 (not
// power-of-two).
uint32_t longer_side(double texels, double r) { return std::max<uint32_t>(1, uint32_t(std::lround(std::sqrt(texels * r)))); }

// The atlas of `texels` image texels at `aspect` (width / height), sized as
// choose_at_aspect sizes it for CostMeasure::ImageTexels without pot.
std::array<uint32_t, 2> image_dims(double aspect, double texels, uint32_t block) {
  SizeRule rule;
  rule.aspect = aspect;
  rule.block = block;
  return rule.dims(longer_side(texels, aspect >= 1 ? aspect : 1 / aspect), texels);
}

}  // namespace

namespace {

// choose_atlas at one aspect ratio (width / height).
Packing choose_at_aspect(const std::vector<ChartShape>& charts, double area1, uint32_t old_width, uint32_t old_height,
                         double old_used_texels, const BudgetOptions& o, double aspect) {
  Packing p;
  SizeRule rule;
  rule.aspect = aspect;
  rule.pot = o.pot;
  rule.block = side_unit(o);
  const double r = rule.aspect >= 1 ? rule.aspect : 1 / rule.aspect;

  Prints prints;  // the last scale's footprints, reused while only the atlas size changes
  prints.scale = -1;
  auto prints_at = [&](double s) -> const Prints& {
    if (prints.scale != s) prints = rasterize_all(charts, s, o.pack);
    return prints;
  };
  auto fits_at = [&](uint32_t L, double s) {
    auto d = rule.dims(L);
    return place_any(prints_at(s), d[0], d[1], o.pack);
  };
  // Smallest longer side (non-pot) holding the charts at scale s; 0 if none <= kMaxSide.
  // known: a side known to hold them (0: none), which bounds the search from above.
  auto smallest_side = [&](double s, uint32_t known = 0) -> uint32_t {
    // Area bound: the texels under the charts (overlaps once) must fit in the image.
    uint32_t lo = std::max<uint32_t>(1, uint32_t(std::sqrt(prints_at(s).covered * r)));
    if (lo > 1) --lo;
    if (known > 0 && known <= lo) return known;
    uint32_t hi = known > 0 ? known : std::max<uint32_t>(lo + 1, 2);
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

  if (o.size > 0) {
    const uint32_t L = o.pot ? rule.nearest_pot(o.size) : o.size;
    auto d = rule.dims(L);
    p = pack_max_scale(charts, d[0], d[1], o.pack, o.s_max);
  } else if (o.measure == CostMeasure::ChartTexels && old_used_texels > 0 && area1 > 0) {
    // Pinned charts keep their area (scale 1); the others' scale spends what is left.
    const double pinned = chart_area(charts, true);
    const double left = o.cost * old_used_texels - pinned;
    if (left < 0 || (area1 > pinned && left <= 0)) return p;  // the pinned charts alone overspend the budget
    const double s = area1 > pinned ? std::min(o.s_max, std::sqrt(left / (area1 - pinned))) : o.s_max;
    const uint32_t L = smallest_side(s);
    if (L == 0) return p;
    if (o.pot) {
      auto d = rule.dims(rule.nearest_pot(L));
      p = pack_max_scale(charts, d[0], d[1], o.pack, o.s_max);
    } else {
      p = fits_at(L, s);
    }
  } else {
    const double texels = o.cost * double(old_width) * old_height;
    uint32_t L = o.pot ? rule.nearest_pot(std::sqrt(texels * r)) : longer_side(texels, r);
    auto d = rule.dims(L, texels);
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
        const uint32_t Ls = smallest_side(o.s_max, L);
        if (Ls > 0 && Ls < L) p = fits_at(Ls, o.s_max);
      }
    }
  }
  return p;
}

}  // namespace

AtlasChoice choose_atlas(const std::vector<ChartShape>& charts, uint32_t old_width, uint32_t old_height,
                         double old_used_texels, const BudgetOptions& o) {
  AtlasChoice choice;
  const double area1 = chart_area(charts);
  const double source = old_width > 0 && old_height > 0 ? double(old_width) / old_height : 1.0;
  // With the aspect free: 2:1 and 1:2 of the source's beside it, then 4:1 (1:4) where 2:1
  // (1:2) won, so a long chart gets a long atlas without trying every shape every time.
  auto better = [](const Packing& p, const Packing* than) {
    // The largest scale (more texels per chart), then the fewest image texels; a shape
    // other than the source's must win by 1 % (than is always the earlier in the list).
    if (!p.ok) return false;
    if (!than) return true;
    if (p.scale > than->scale * 1.01) return true;
    return p.scale >= than->scale * (1 - 1e-9) && double(p.width) * p.height < 0.99 * double(than->width) * than->height;
  };
  std::vector<double> aspects{source};
  if (!o.keep_aspect) aspects.insert(aspects.end(), {source * 2, source / 2});
  std::vector<Packing> found(aspects.size());
  // Independent searches, compared in list order: the result does not depend on threads.
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < int(aspects.size()); ++k)
    found[size_t(k)] = choose_at_aspect(charts, area1, old_width, old_height, old_used_texels, o, aspects[size_t(k)]);
  if (!o.keep_aspect) {
    const bool wide = better(found[1], &found[0]) && !better(found[2], &found[1]);
    const bool tall = better(found[2], &found[0]) && !better(found[1], &found[2]);
    if (wide || tall) {
      aspects.push_back(source * (wide ? 4 : 0.25));
      found.push_back(choose_at_aspect(charts, area1, old_width, old_height, old_used_texels, o, aspects.back()));
    }
  }
  Packing* best = nullptr;
  for (Packing& p : found)
    if (better(p, best)) best = &p;
  if (!best) return choice;
  // More shapes: the bottom-left fill fills some shapes a few points better than their
  // neighbours, and which ones depends on the charts. Tried: the steps of 2^(1/4) between
  // 1:2 and 2:1 of the source's (to 1:4, 4:1 where those won), the largest chart's own
  // shape (with its gutter) both ways round, then steps of 2^(1/8) and 2^(1/16) about the
  // best. bench pack, own charts at half the texels, gutter 4: Duck's efficiency 0.67 ->
  // 0.74 (a 1.19:1 atlas, scale 0.743 -> 0.780), MultiUVTest's 0.37 -> 0.49; Fox and the
  // truck keep their shapes. A shape is searched in full (a bisection on the scale) only
  // where one placement with the first strategy holds the charts at 1 % more scale than the
  // best so far (or, within 1 % of the source density, in 1 % fewer image texels), on
  // footprints rasterized once per best scale; most shapes stop there, and a packing takes
  // 1-2x as long as with the three shapes alone.
  std::deque<Packing> tried;  // the refinement's winners; `best` may point here
  if (!o.keep_aspect && !o.pot && o.size == 0 && o.measure == CostMeasure::ImageTexels) {
    double best_aspect = aspects[size_t(best - found.data())];
    const uint32_t block = side_unit(o);
    Prints probe;  // the footprints at the probe's scale, kept while the best does not change
    probe.scale = -1;
    auto try_shapes = [&](const std::vector<double>& shapes) {
      // Within 1 % of the source density a shape can only win by holding the charts at
      // that density in 1 % fewer image texels (`better`): the probe asks that instead.
      const bool capped = best->scale * 1.01 > o.s_max;
      const double probe_scale = capped ? o.s_max : best->scale * 1.01;
      const double texels = capped ? 0.99 * double(best->width) * best->height : o.cost * double(old_width) * old_height;
      if (probe.scale != probe_scale) probe = rasterize_all(charts, probe_scale, o.pack);
      std::vector<Packing> round(shapes.size());
#pragma omp parallel for schedule(dynamic, 1)
      for (int k = 0; k < int(shapes.size()); ++k) {
        const auto d = image_dims(shapes[size_t(k)], texels, block);
        if (!place(probe, d[0], d[1], o.pack, kStrategies[0]).ok) continue;
        round[size_t(k)] = choose_at_aspect(charts, area1, old_width, old_height, old_used_texels, o, shapes[size_t(k)]);
      }
      for (size_t k = 0; k < shapes.size(); ++k)
        if (better(round[k], best)) tried.push_back(std::move(round[k])), best = &tried.back(), best_aspect = shapes[k];
    };
    const int reach = best_aspect > source * 3 || best_aspect < source / 3 ? 8 : 4;  // 4:1 (1:4) was tried and won
    std::vector<double> shapes;
    for (int k = -reach; k <= reach; ++k)
      if (k % 4 != 0) shapes.push_back(source * std::exp2(0.25 * k));
    if (!charts.empty()) {  // the largest chart (by area): its box at the best's scale, and the gutter
      size_t largest = 0;
      double largest_area = -1;
      for (size_t i = 0; i < charts.size(); ++i) {
        const double a = chart_area(charts[i]);
        if (a > largest_area) largest_area = a, largest = i;
      }
      const std::vector<double>& pts = charts[largest].points;
      double mx = std::numeric_limits<double>::infinity(), my = mx, Mx = -mx, My = -mx;
      for (size_t i = 0; i + 1 < pts.size(); i += 2)
        mx = std::min(mx, pts[i]), Mx = std::max(Mx, pts[i]), my = std::min(my, pts[i + 1]), My = std::max(My, pts[i + 1]);
      const double sl = charts[largest].pinned ? 1.0 : best->scale;
      const double own = ((Mx - mx) * sl + o.pack.gutter) / ((My - my) * sl + o.pack.gutter);
      if (own > 0 && std::isfinite(own)) shapes.push_back(own), shapes.push_back(1 / own);
    }
    try_shapes(shapes);
    for (const double step : {std::exp2(0.125), std::exp2(0.0625)}) try_shapes({best_aspect / step, best_aspect * step});
  }
  choice.packing = std::move(*best);
  const Packing& q = choice.packing;
  if (old_used_texels > 0) choice.cost_ratio = q.chart_area / old_used_texels;
  if (old_width > 0 && old_height > 0) choice.texel_ratio = double(q.width) * q.height / (double(old_width) * old_height);
  return choice;
}

}  // namespace uvpress::atlas
