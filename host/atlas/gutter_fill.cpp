#include "atlas/gutter_fill.h"

#include "atlas/rebake.h"  // the sRGB conversions every bake shares

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <limits>

namespace uvpress::atlas {

namespace {

// Nearest covered texel for every texel (exact squared Euclidean distance transform,
// Felzenszwalb & Huttenlocher): columns, then the lower envelope of parabolas per row.
std::vector<int64_t> nearest_covered(const std::vector<uint8_t>& covered, int W, int H) {
  std::vector<int32_t> col(size_t(W) * H, -1);  // nearest covered row in the same column
#pragma omp parallel for schedule(static)
  for (int x = 0; x < W; ++x) {
    int last = -1;
    for (int y = 0; y < H; ++y) {
      if (covered[size_t(y) * W + x]) last = y;
      col[size_t(y) * W + x] = last;
    }
    last = -1;
    for (int y = H - 1; y >= 0; --y) {
      if (covered[size_t(y) * W + x]) last = y;
      int32_t& c = col[size_t(y) * W + x];
      if (last >= 0 && (c < 0 || last - y < y - c)) c = last;
    }
  }
  std::vector<int64_t> nearest(size_t(W) * H, -1);
#pragma omp parallel
  {
    std::vector<int> v(W);
    std::vector<double> z(W + 1);
#pragma omp for schedule(static)
    for (int y = 0; y < H; ++y) {
      auto h = [&](int q) {
        const double d = double(y - col[size_t(y) * W + q]);
        return d * d;
      };
      int k = -1;
      for (int q = 0; q < W; ++q) {
        if (col[size_t(y) * W + q] < 0) continue;
        const double fq = h(q) + double(q) * q;
        double s = 0;
        while (k >= 0) {
          const int p = v[k];
          s = (fq - (h(p) + double(p) * p)) / (2.0 * (q - p));
          if (s <= z[k]) {
            --k;
          } else {
            break;
          }
        }
        ++k;
        v[k] = q;
        z[k] = k == 0 ? -std::numeric_limits<double>::infinity() : s;
        z[k + 1] = std::numeric_limits<double>::infinity();
      }
      if (k < 0) continue;
      int j = 0;
      for (int x = 0; x < W; ++x) {
        while (z[j + 1] < x) ++j;
        const int q = v[j];
        nearest[size_t(y) * W + x] = int64_t(col[size_t(y) * W + q]) * W + q;
      }
    }
  }
  return nearest;
}

// 8-connected components of the texels with known != 0: labels 0, 1, ... in scan order of
// each component's first texel; -1 where unknown.
std::vector<int32_t> components(const std::vector<uint8_t>& known, int W, int H) {
  std::vector<int32_t> label(size_t(W) * H, -1);
  std::vector<int64_t> stack;
  int32_t next = 0;
  for (int64_t i = 0; i < int64_t(W) * H; ++i) {
    if (!known[size_t(i)] || label[size_t(i)] >= 0) continue;
    label[size_t(i)] = next;
    stack.push_back(i);
    while (!stack.empty()) {
      const int64_t j = stack.back();
      stack.pop_back();
      const int x = int(j % W), y = int(j / W);
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int u = x + dx, v = y + dy;
          if (u < 0 || v < 0 || u >= W || v >= H) continue;
          const size_t k = size_t(v) * W + u;
          if (known[k] && label[k] < 0) label[k] = next, stack.push_back(int64_t(k));
        }
    }
    ++next;
  }
  return label;
}

constexpr int32_t kEmpty = -1, kSeveral = -2;

// One level of the pyramid: per block its mean over non-empty children (C floats) and what
// it holds (a component, kEmpty or kSeveral).
struct Level {
  int w = 0, h = 0;
  std::vector<float> mean;
  std::vector<int32_t> holds;
};

}  // namespace

void fill_gutter(Image& image, const std::vector<uint8_t>& covered, bool srgb, uint32_t ring) {
  const int W = int(image.width), H = int(image.height), C = int(image.channels);
  const size_t N = size_t(W) * H;
  if (covered.size() != N || C == 0) return;
  size_t count = 0;
  for (uint8_t c : covered) count += c != 0;
  if (count == 0 || count == N) return;
  const int colour = srgb ? (C == 2 || C == 4 ? C - 1 : C) : 0;  // channels averaged in linear light

  // 1. The ring, and every empty texel's nearest chart texel (used again in 2).
  const std::vector<int64_t> nearest = nearest_covered(covered, W, H);
  std::vector<uint8_t> known(covered.begin(), covered.end());
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < int64_t(N); ++i) {
    const int64_t n = nearest[size_t(i)];
    if (covered[size_t(i)] || n < 0) continue;
    const int64_t dx = i % W - n % W, dy = i / W - n / W;
    if (std::max(std::abs(dx), std::abs(dy)) > int64_t(ring)) continue;
    std::copy_n(&image.pixels[size_t(n) * C], C, &image.pixels[size_t(i) * C]);
    known[size_t(i)] = 1;
  }

  // 2. Pull: level 0 is the image (linear light where asked), then 2x2 blocks up to 1x1.
  std::vector<Level> levels(1);
  levels[0].w = W, levels[0].h = H;
  levels[0].mean.assign(image.pixels.begin(), image.pixels.end());
  if (colour > 0)
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < int64_t(N); ++i)
      for (int c = 0; c < colour; ++c) levels[0].mean[size_t(i) * C + c] = srgb_decode_fast(levels[0].mean[size_t(i) * C + c]);
  levels[0].holds = components(known, W, H);
  while (levels.back().w > 1 || levels.back().h > 1) {
    const Level& f = levels.back();
    Level p;
    p.w = (f.w + 1) / 2, p.h = (f.h + 1) / 2;
    p.mean.assign(size_t(p.w) * p.h * C, 0.0f);
    p.holds.assign(size_t(p.w) * p.h, kEmpty);
#pragma omp parallel for schedule(static)
    for (int y = 0; y < p.h; ++y)
      for (int x = 0; x < p.w; ++x) {
        const size_t b = size_t(y) * p.w + x;
        int n = 0;
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx) {
            const int u = 2 * x + dx, v = 2 * y + dy;
            if (u >= f.w || v >= f.h) continue;
            const size_t k = size_t(v) * f.w + u;
            const int32_t h = f.holds[k];
            if (h == kEmpty) continue;
            ++n;
            for (int c = 0; c < C; ++c) p.mean[b * C + c] += f.mean[k * C + c];
            int32_t& mine = p.holds[b];
            mine = mine == kEmpty ? h : (mine == h ? h : kSeveral);
          }
        if (n > 1)
          for (int c = 0; c < C; ++c) p.mean[b * C + c] /= float(n);
      }
    levels.push_back(std::move(p));
  }

  // Push: for every empty block, the value it takes, from the top down: the mean of its
  // smallest non-empty ancestor when that holds one chart, else "nearest" (a flag).
  // fill[k] holds C floats per block of level k; use_nearest[k] the flag.
  const size_t top = levels.size() - 1;
  std::vector<float> fill_above, fill_here;
  std::vector<uint8_t> nearest_above, nearest_here;
  for (size_t k = top; k-- > 0;) {
    const Level& L = levels[k];
    const Level& P = levels[k + 1];
    fill_here.assign(size_t(L.w) * L.h * C, 0.0f);
    nearest_here.assign(size_t(L.w) * L.h, 0);
#pragma omp parallel for schedule(static)
    for (int y = 0; y < L.h; ++y)
      for (int x = 0; x < L.w; ++x) {
        const size_t b = size_t(y) * L.w + x;
        if (L.holds[b] != kEmpty) continue;
        const size_t q = size_t(y / 2) * P.w + size_t(x / 2);
        if (P.holds[q] >= 0) {
          std::copy_n(&P.mean[q * C], C, &fill_here[b * C]);
        } else if (P.holds[q] == kSeveral) {
          nearest_here[b] = 1;
        } else {  // the parent is empty too (never at the top: something is covered)
          std::copy_n(&fill_above[q * C], C, &fill_here[b * C]);
          nearest_here[b] = nearest_above[q];
        }
      }
    std::swap(fill_above, fill_here);
    std::swap(nearest_above, nearest_here);
  }
  // Level 0: fill_above and nearest_above now hold the values of the empty texels.
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < int64_t(N); ++i) {
    if (known[size_t(i)]) continue;
    float* to = &image.pixels[size_t(i) * C];
    if (nearest_above[size_t(i)]) {
      if (nearest[size_t(i)] >= 0) std::copy_n(&image.pixels[size_t(nearest[size_t(i)]) * C], C, to);
      continue;
    }
    const float* v = &fill_above[size_t(i) * C];
    for (int c = 0; c < C; ++c) to[c] = c < colour ? srgb_encode_fast(v[c]) : v[c];
  }
}

void coarsen_gutter(Image& image, const std::vector<uint8_t>& footprint, bool srgb, bool wrap_x, bool wrap_y,
                    uint32_t max_block) {
  const int W = int(image.width), H = int(image.height), C = int(image.channels);
  const size_t N = size_t(W) * H;
  if (footprint.size() != N || C == 0 || N == 0) return;
  // The coarsest block B = 2^L: at most max_block (and 128: distances are bytes), and
  // dividing both sides.
  int L = 0;
  while ((2u << L) <= std::min(max_block, 128u) && W % (2 << L) == 0 && H % (2 << L) == 0) ++L;
  if (L == 0) return;
  const int B = 1 << L;
  const int colour = srgb ? (C == 2 || C == 4 ? C - 1 : C) : 0;

  // Chebyshev distance to the footprint, up to B (farther is all alike: level L): a
  // breadth-first search over 8-neighbours from every footprint texel at once (exact for this
  // metric), wrapping across the edges asked for.
  std::vector<uint8_t> d(N, uint8_t(B));
  std::vector<uint32_t> queue;
  for (size_t i = 0; i < N; ++i)
    if (footprint[i]) d[i] = 0, queue.push_back(uint32_t(i));
  if (queue.empty()) return;
  for (size_t head = 0; head < queue.size(); ++head) {
    const uint32_t i = queue[head];
    if (d[i] + 1 >= B) continue;
    const int x = int(i % uint32_t(W)), y = int(i / uint32_t(W));
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        int u = x + dx, v = y + dy;
        if (u < 0 || u >= W) {
          if (!wrap_x) continue;
          u = (u + W) % W;
        }
        if (v < 0 || v >= H) {
          if (!wrap_y) continue;
          v = (v + H) % H;
        }
        const size_t k = size_t(v) * W + u;
        if (d[k] == B) d[k] = uint8_t(d[i] + 1), queue.push_back(uint32_t(k));
      }
  }
  // A texel's level j: 2^j the largest power of two <= its distance, at most B (0: kept).
  uint8_t level_of[256] = {};
  for (int t = 2; t <= B; ++t) level_of[t] = uint8_t(level_of[t / 2] + 1);

  // Tile by tile (B x B, so that every block lies in one): per level and block the sum and
  // count of the texels that take that block's mean, then the means.
  auto linear = [&](float v, int c) { return c < colour ? double(srgb_decode_fast(v)) : double(v); };
  std::vector<double> sum;
  std::vector<uint32_t> count;
  std::vector<size_t> offset(size_t(L) + 2, 0);  // level j's blocks start at offset[j]
  for (int j = 1; j <= L; ++j) offset[size_t(j) + 1] = offset[size_t(j)] + size_t(B >> j) * size_t(B >> j);
  for (int ty = 0; ty < H; ty += B)
    for (int tx = 0; tx < W; tx += B) {
      sum.assign(offset[size_t(L) + 1] * C, 0.0);
      count.assign(offset[size_t(L) + 1], 0);
      // Every flattened texel of the tile with its level's block.
      auto each = [&](auto&& visit) {
        for (int y = ty; y < ty + B; ++y)
          for (int x = tx; x < tx + B; ++x) {
            const size_t i = size_t(y) * W + x;
            if (const int j = level_of[d[i]])
              visit(i, offset[size_t(j)] + size_t((y - ty) >> j) * size_t(B >> j) + size_t((x - tx) >> j));
          }
      };
      each([&](size_t i, size_t b) {
        ++count[b];
        for (int c = 0; c < C; ++c) sum[b * C + c] += linear(image.pixels[i * C + c], c);
      });
      each([&](size_t i, size_t b) {
        for (int c = 0; c < C; ++c) {
          const float m = float(sum[b * C + c] / count[b]);
          image.pixels[i * C + c] = c < colour ? srgb_encode_fast(m) : m;
        }
      });
    }
}

uint32_t mip_safe_gutter(double image_texels, uint32_t coarsest_side, uint32_t minimum, uint32_t maximum) {
  const double side = std::sqrt(std::max(image_texels, 1.0));
  uint32_t g = 1;
  while (g < maximum && side / g > double(std::max(coarsest_side, 1u)) + 1e-9) g *= 2;
  return std::clamp(g, minimum, std::max(minimum, maximum));
}

}  // namespace uvpress::atlas
