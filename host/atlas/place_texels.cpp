#include "atlas/place_texels.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace uvpress::atlas {

size_t copy_chart_texels(const Image& resized, const ChartShape& shape, const Packing& packing, size_t index,
                         uint32_t dilation, Image& atlas, std::vector<uint8_t>* copied_mask) {
  if (index >= packing.placements.size() || resized.channels != atlas.channels) return 0;
  if (copied_mask && copied_mask->size() != size_t(atlas.width) * atlas.height) copied_mask = nullptr;
  const ChartPlacement& pl = packing.placements[index];
  const long tx = std::lround(pl.tx), ty = std::lround(pl.ty);
  const size_t n = shape.points.size() / 2;
  const int W = int(atlas.width), H = int(atlas.height), d = int(dilation);
  // Footprint in the placement's box (grown by the dilation), then dilated.
  const int x0 = std::max(0, int(pl.x) - d - 1), y0 = std::max(0, int(pl.y) - d - 1);
  const int x1 = std::min(W, int(pl.x + pl.width) + d + 1), y1 = std::min(H, int(pl.y + pl.height) + d + 1);
  if (x1 <= x0 || y1 <= y0) return 0;
  const int bw = x1 - x0, bh = y1 - y0;
  std::vector<uint8_t> mask(size_t(bw) * size_t(bh), 0);
  for (size_t t = 0; t + 2 < shape.triangles.size(); t += 3) {
    double v[3][2];
    bool bad = false;
    for (int k = 0; k < 3; ++k) {
      const uint32_t i = shape.triangles[t + size_t(k)];
      if (i >= n) {
        bad = true;
        break;
      }
      auto q = packing.map(index, shape.points[2 * i], shape.points[2 * i + 1]);
      v[k][0] = q[0], v[k][1] = q[1];
    }
    if (bad) continue;
    const int lx = std::max(x0, int(std::floor(std::min({v[0][0], v[1][0], v[2][0]}))));
    const int hx = std::min(x1 - 1, int(std::ceil(std::max({v[0][0], v[1][0], v[2][0]}))));
    const int ly = std::max(y0, int(std::floor(std::min({v[0][1], v[1][1], v[2][1]}))));
    const int hy = std::min(y1 - 1, int(std::ceil(std::max({v[0][1], v[1][1], v[2][1]}))));
    for (int y = ly; y <= hy; ++y)
      for (int x = lx; x <= hx; ++x)
        if (triangle_overlaps_box(v[0], v[1], v[2], x, y, x + 1, y + 1)) mask[size_t(y - y0) * size_t(bw) + size_t(x - x0)] = 1;
  }
  if (d > 0) {  // Chebyshev dilation, separable: rows then columns
    std::vector<uint8_t> tmp(mask.size(), 0);
    for (int y = 0; y < bh; ++y)
      for (int x = 0; x < bw; ++x)
        if (mask[size_t(y) * size_t(bw) + size_t(x)])
          for (int k = std::max(0, x - d); k <= std::min(bw - 1, x + d); ++k) tmp[size_t(y) * size_t(bw) + size_t(k)] = 1;
    std::fill(mask.begin(), mask.end(), 0);
    for (int y = 0; y < bh; ++y)
      for (int x = 0; x < bw; ++x)
        if (tmp[size_t(y) * size_t(bw) + size_t(x)])
          for (int k = std::max(0, y - d); k <= std::min(bh - 1, y + d); ++k) mask[size_t(k) * size_t(bw) + size_t(x)] = 1;
  }
  // Atlas texel (i, j) <- resized texel, inverting atlas = R_k p + t at texel centres:
  // k = 0: (i - tx, j - ty); k = 1 (R (x, y) = (-y, x)): (j - ty, tx - i - 1);
  // k = 2: (tx - i - 1, ty - j - 1); k = 3: (ty - j - 1, i - tx).
  size_t copied = 0;
  const uint32_t C = atlas.channels;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      if (!mask[size_t(y - y0) * size_t(bw) + size_t(x - x0)]) continue;
      long sx = x - tx, sy = y - ty;
      if (pl.rotation == 1) sx = y - ty, sy = tx - x - 1;
      if (pl.rotation == 2) sx = tx - x - 1, sy = ty - y - 1;
      if (pl.rotation == 3) sx = ty - y - 1, sy = x - tx;
      if (sx < 0 || sy < 0 || sx >= long(resized.width) || sy >= long(resized.height)) continue;
      const float* from = &resized.pixels[(size_t(sy) * resized.width + size_t(sx)) * C];
      std::copy(from, from + C, &atlas.pixels[(size_t(y) * atlas.width + size_t(x)) * C]);
      if (copied_mask) (*copied_mask)[size_t(y) * atlas.width + size_t(x)] = 1;
      ++copied;
    }
  return copied;
}

}  // namespace uvpress::atlas
