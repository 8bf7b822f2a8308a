// Re-bake sampling on the CPU: the oracle for rebake.comp and the CPU backend's
// Engine::rebake_texels. Double precision throughout; every texel depends only on the
// description, never on which thread ran it, so results are identical for any thread count.
#include "backend.h"
#include "parallel_for.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace uvpress::engine {

int rebake_wrap(int i, int n, int mode) {
  if (mode == kRebakeWrapClampToEdge) return std::clamp(i, 0, n - 1);
  if (mode == kRebakeWrapMirroredRepeat) {
    int m = i % (2 * n);
    if (m < 0) m += 2 * n;
    return m < n ? m : 2 * n - 1 - m;
  }
  int m = i % n;  // REPEAT (and anything unknown)
  return m < 0 ? m + n : m;
}

void check_rebake_texels(const RebakeTexelsDesc& d) {
  auto fail = [](const std::string& what) { throw EngineError("rebake_texels: " + what); };
  if (d.width == 0 || d.height == 0) fail("zero output size");
  if (d.source_width == 0 || d.source_height == 0 || !d.source) fail("empty source");
  if (d.channels < 1 || d.channels > 4) fail("channels must be 1..4");
  if (d.premultiplied && d.channels != 2 && d.channels != 4) fail("premultiplied needs 2 or 4 channels");
  if (uint64_t(d.source_width) * d.source_height > 0x7fffffffull) fail("source too large");
  if (d.width > 0x7fff0000u || d.height > 0x7fff0000u) fail("output too large");
  if (!d.tile_start || !d.owner || (d.triangle_count > 0 && !d.triangles)) fail("missing arrays");
  const uint64_t tiles = uint64_t((d.width + kRebakeTile - 1) / kRebakeTile) * ((d.height + kRebakeTile - 1) / kRebakeTile);
  if (d.tile_start[0] != 0) fail("tile_start[0] must be 0");
  if (d.tile_start[tiles] > 0 && !d.tile_list) fail("missing tile_list");
  for (uint64_t k = 0; k < tiles; ++k)
    if (d.tile_start[k + 1] < d.tile_start[k]) fail("tile_start must not decrease");
  for (uint32_t k = 0; k < d.tile_start[tiles]; ++k)
    if (d.tile_list[k] >= d.triangle_count) fail("tile_list names a missing triangle");
  for (size_t t = 0; t < d.triangle_count; ++t)
    if (d.triangles[t].ns[0] < 1 || d.triangles[t].ns[1] < 1 || d.triangles[t].ns[0] > 65535 ||
        d.triangles[t].ns[1] > 65535)
      fail("samples per axis must be 1..65535");
  const uint32_t tx = (d.width + kRebakeTile - 1) / kRebakeTile;
  for (uint32_t y = 0; y < d.height; ++y)
    for (uint32_t x = 0; x < d.width; ++x) {
      const uint32_t o = d.owner[size_t(y) * d.width + x];
      if (o == kRebakeNoOwner) continue;
      const uint32_t tile = (y / kRebakeTile) * tx + x / kRebakeTile;
      if (o < d.tile_start[tile] || o >= d.tile_start[tile + 1]) fail("an owner outside its texel's tile list");
    }
}

double rebake_closest_point(const RebakeTriangle& t, double px, double py, double& qx, double& qy) {
  bool inside = true;
  for (int e = 0; e < 3; ++e) {
    const double* a = t.n[e];
    const double* b = t.n[(e + 1) % 3];
    const double ef = ((b[0] - a[0]) * (py - a[1]) - (b[1] - a[1]) * (px - a[0])) * t.sign;
    if (ef < 0) {
      inside = false;
      break;
    }
  }
  if (inside) {
    qx = px, qy = py;
    return 0;
  }
  double best = std::numeric_limits<double>::infinity();
  for (int e = 0; e < 3; ++e) {
    const double* a = t.n[e];
    const double* b = t.n[(e + 1) % 3];
    const double dx = b[0] - a[0], dy = b[1] - a[1];
    const double len2 = dx * dx + dy * dy;
    double s = len2 > 0 ? ((px - a[0]) * dx + (py - a[1]) * dy) / len2 : 0;
    s = std::clamp(s, 0.0, 1.0);
    const double cx = a[0] + s * dx, cy = a[1] + s * dy;
    const double d = (px - cx) * (px - cx) + (py - cy) * (py - cy);
    if (d < best) best = d, qx = cx, qy = cy;
  }
  return best;
}

void rebake_filter_box(const RebakeTexelsDesc& d, const RebakeTriangle& t, const uint32_t* first,
                       const uint32_t* last, double bx, double by, double* out, double size) {
  const int SW = int(d.source_width), SH = int(d.source_height);
  const int C = int(d.channels);
  const int alpha = C - 1;
  const int colour_channels = d.premultiplied ? C - 1 : C;
  const float* src = d.source;
  double acc[4], straight[4];
  // straight: colour un-premultiplied per texel (for footprints that are fully
  // transparent, whose premultiplied colour is 0/0).
  auto accumulate = [&](double* sum, bool straight_pass) {
    std::fill(sum, sum + 4, 0.0);
    for (int j = 0; j < t.ns[1]; ++j)
      for (int i = 0; i < t.ns[0]; ++i) {
        const double px = bx + size * (i + 0.5) / t.ns[0], py = by + size * (j + 0.5) / t.ns[1];
        // The sample's own triangle: the owner, else the first candidate that
        // contains it (a neighbour across an inner edge), else the owner's closest
        // point (outside every chart: never read beyond the source chart).
        const RebakeTriangle* st = &t;
        double qx, qy;
        if (rebake_closest_point(t, px, py, qx, qy) > 0) {
          for (const uint32_t* it = first; it != last; ++it) {
            const RebakeTriangle& u = d.triangles[*it];
            if (&u == &t || px < u.lo[0] || px > u.hi[0] || py < u.lo[1] || py > u.hi[1]) continue;
            double rx, ry;
            if (rebake_closest_point(u, px, py, rx, ry) == 0) {
              st = &u, qx = px, qy = py;
              break;
            }
          }
        }
        const double dx = qx - st->n[0][0], dy = qy - st->n[0][1];
        const double ox = st->o0[0] + st->J[0][0] * dx + st->J[0][1] * dy - 0.5;
        const double oy = st->o0[1] + st->J[1][0] * dx + st->J[1][1] * dy - 0.5;
        const double fx = std::floor(ox), fy = std::floor(oy);
        const double wx = ox - fx, wy = oy - fy;
        const int x0 = rebake_wrap(int(fx), SW, d.wrap_s), x1 = rebake_wrap(int(fx) + 1, SW, d.wrap_s);
        const int y0 = rebake_wrap(int(fy), SH, d.wrap_t), y1 = rebake_wrap(int(fy) + 1, SH, d.wrap_t);
        const float* p[4] = {src + (size_t(y0) * SW + x0) * C, src + (size_t(y0) * SW + x1) * C,
                             src + (size_t(y1) * SW + x0) * C, src + (size_t(y1) * SW + x1) * C};
        const double w[4] = {(1 - wx) * (1 - wy), wx * (1 - wy), (1 - wx) * wy, wx * wy};
        for (int k = 0; k < 4; ++k) {
          if (straight_pass) {
            const double a = p[k][alpha];
            for (int c = 0; c < colour_channels; ++c) sum[c] += w[k] * (a > 0 ? p[k][c] / a : 0.0);
          } else {
            for (int c = 0; c < C; ++c) sum[c] += w[k] * p[k][c];
          }
        }
      }
  };
  const double inv = 1.0 / (t.ns[0] * t.ns[1]);
  accumulate(acc, false);
  if (d.premultiplied) {
    const double a = acc[alpha] * inv;
    if (!(a > 1e-7)) accumulate(straight, true);
    for (int c = 0; c < colour_channels; ++c) out[c] = a > 1e-7 ? acc[c] * inv / a : straight[c] * inv;
    out[alpha] = a;
  } else {
    for (int c = 0; c < C; ++c) out[c] = acc[c] * inv;
  }
}

void rebake_texels_cpu(const RebakeTexelsDesc& d, float* texels, unsigned threads) {
  check_rebake_texels(d);
  const int W = int(d.width), H = int(d.height);
  const int C = int(d.channels);
  const int T = int(kRebakeTile);
  const int tx = (W + T - 1) / T, ty = (H + T - 1) / T;

  auto run_tile = [&](int tile) {
    const int bx = (tile % tx) * T, by = (tile / tx) * T;
    const uint32_t* first = d.tile_list + d.tile_start[tile];
    const uint32_t* last = d.tile_list + d.tile_start[tile + 1];
    if (first == last) return;
    double f[4];
    for (int y = by; y < std::min(H, by + T); ++y)
      for (int x = bx; x < std::min(W, bx + T); ++x) {
        const uint32_t own = d.owner[size_t(y) * W + x];
        if (own == kRebakeNoOwner) continue;
        rebake_filter_box(d, d.triangles[d.tile_list[own]], first, last, x, y, f);
        float* o = texels + (size_t(y) * W + x) * C;
        for (int c = 0; c < C; ++c) o[c] = float(f[c]);
      }
  };

  parallel_for(uint32_t(tx * ty), threads, [&](uint32_t tile) { run_tile(int(tile)); }, 1);
}

}  // namespace uvpress::engine
