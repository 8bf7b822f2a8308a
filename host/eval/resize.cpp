// Texture resizing as users' tools do (see resize.h).
#include "resize.h"

#include "atlas/rebake.h"
#include "core/parallel.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace uvpress::eval {

namespace {

// One axis of a separable resize: output k reads `count` input indices with their weights
// (summing to 1; shorter rows padded with weight-0 taps, which leave every sum's bits alone).
struct AxisTaps {
  uint32_t count = 0;              // taps per output texel
  std::vector<uint32_t> index;     // to * count input texels
  std::vector<double> weight;      // to * count
};

// Exact box (area) weights per output index when shrinking, linear interpolation between
// texel centres (clamped) when enlarging, the identity at the same size.
AxisTaps area_taps(uint32_t from, uint32_t to) {
  std::vector<std::vector<std::pair<uint32_t, double>>> w(to);
  const double scale = double(from) / to;
  for (uint32_t k = 0; k < to; ++k) {
    if (from == to) {
      w[k] = {{k, 1.0}};
    } else if (to < from) {
      const double a = k * scale, b = (k + 1) * scale;
      for (uint32_t i = uint32_t(std::floor(a)); i < std::min<uint32_t>(from, uint32_t(std::ceil(b))); ++i) {
        const double overlap = std::min(b, i + 1.0) - std::max(a, double(i));
        if (overlap > 0) w[k].push_back({i, overlap / scale});
      }
    } else {
      const double s = std::clamp((k + 0.5) * scale - 0.5, 0.0, double(from - 1));
      const uint32_t i0 = uint32_t(std::floor(s)), i1 = std::min(i0 + 1, from - 1);
      const double f = s - i0;
      w[k] = {{i0, 1 - f}, {i1, f}};
    }
  }
  AxisTaps t;
  for (const auto& taps : w) t.count = std::max(t.count, uint32_t(taps.size()));
  t.index.assign(size_t(to) * t.count, 0), t.weight.assign(size_t(to) * t.count, 0.0);
  for (uint32_t k = 0; k < to; ++k)
    for (size_t i = 0; i < w[k].size(); ++i)
      t.index[size_t(k) * t.count + i] = w[k][i].first, t.weight[size_t(k) * t.count + i] = w[k][i].second;
  return t;
}

// Lanczos-3 taps of one axis, as OpenImageIO's resize places them: output texel k samples
// the input at c = (k + 0.5) from / to (input texel units, texel i centred at i + 0.5);
// the kernel spans 3 output texels when shrinking (its argument is the distance in output
// texels) and 3 input texels when enlarging; taps past the ends read the edge texel;
// weights normalized to sum 1. Every output of a row or column shares its axis's taps, so
// they are worked out once per axis instead of per texel (a 1024^2 texture halved: 0.27 s
// through OpenImageIO's per-texel iterators, ~10 ms here).
AxisTaps lanczos3_taps(uint32_t from, uint32_t to) {
  const double ratio = double(to) / from;       // < 1 shrinking
  const double scale = std::min(1.0, ratio);    // kernel argument per input texel of distance
  const int radius = int(std::ceil(3.0 / scale));
  AxisTaps t;
  t.count = uint32_t(2 * radius + 1);
  t.index.resize(size_t(to) * t.count), t.weight.resize(size_t(to) * t.count);
  std::vector<double> w(t.count);
  for (uint32_t k = 0; k < to; ++k) {
    const double c = (k + 0.5) * from / to;
    const int i0 = int(std::floor(c));
    double sum = 0;
    for (int i = 0; i < int(t.count); ++i) {
      double x = std::abs(scale * (i0 - radius + i + 0.5 - c));
      double v = 0;
      if (x < 1e-9) v = 1;
      else if (x < 3) {
        const double px = M_PI * x;
        v = 3 * std::sin(px) * std::sin(px / 3) / (px * px);
      }
      w[size_t(i)] = v, sum += v;
    }
    for (int i = 0; i < int(t.count); ++i) {
      t.index[size_t(k) * t.count + size_t(i)] = uint32_t(std::clamp(i0 - radius + i, 0, int(from) - 1));
      t.weight[size_t(k) * t.count + size_t(i)] = sum != 0 ? w[size_t(i)] / sum : 0.0;
    }
  }
  return t;
}

// The channels that carry colour (sRGB-encoded in colour textures): grey or RGB, never
// alpha (channel 1 of grey+alpha, channel 3 of RGBA).
bool is_colour(uint32_t c, uint32_t channels) { return channels <= 2 ? c == 0 : c < 3; }

// f(v) remembered for the last values seen, per thread, in a direct-mapped table on v's
// bits: the same value as f(v) every time (f is a pure function), without its std::pow
// where values repeat. They do: a resized or mip-mapped texture keeps its flat regions
// flat, and eval decodes and encodes every texel of every cost's chain (pow was ~6 % of
// Fox's eval).
template <float (*F)(float)>
float remembered(float v) {
  constexpr size_t kSlots = 4096;
  struct Memo {
    uint32_t key[kSlots];
    float value[kSlots];
    Memo() {
      // Every slot starts as a genuine entry: all-ones bits (a NaN) and F of it.
      const uint32_t ones = ~uint32_t(0);
      float nan;
      std::memcpy(&nan, &ones, sizeof nan);
      std::fill(key, key + kSlots, ~uint32_t(0)), std::fill(value, value + kSlots, F(nan));
    }
  };
  thread_local Memo memo;
  uint32_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  const size_t slot = (bits * 2654435761u) >> 20;  // Fibonacci hashing to 12 bits
  if (memo.key[slot] != bits) memo.key[slot] = bits, memo.value[slot] = F(v);
  return memo.value[slot];
}

// sRGB decode through a table for the values 8- and 16-bit files hold (k / 65535 covers
// k / 255 exactly); the formula for anything else. Decoding every texel by std::pow would
// cost more than the resize itself on a 4K texture.
float decode(float v) {
  static const std::vector<float> table = [] {
    std::vector<float> t(65536);
    for (int i = 0; i < 65536; ++i) t[size_t(i)] = atlas::srgb_to_linear(float(double(i) / 65535.0));
    return t;
  }();
  const double x = double(v) * 65535.0;
  if (x >= -1.0 && x <= 65536.0) {
    // x rounded to the nearest integer where it is within 1e-3 of one (truncating x + 1/2:
    // std::round is a library call on this target, and a texel a call).
    const double k = double(int32_t(x + 0.5));
    if (k <= 65535 && std::abs(x - k) < 1e-3) return table[size_t(k)];
  }
  return remembered<atlas::srgb_to_linear>(v);
}

float encode(float v) { return remembered<atlas::linear_to_srgb>(v); }

// Every colour channel of `pixels` (C channels a texel) decoded from sRGB, texels spread
// over the threads (each its own: the same result for any thread count).
void decode_colour(std::vector<float>& pixels, uint32_t C) {
  decode(0.0f);  // the table built before the threads share it
#pragma omp parallel for schedule(static) if (worth_threads(long(pixels.size())))
  for (long k = 0; k < long(pixels.size()); ++k)
    if (is_colour(uint32_t(size_t(k) % C), C)) pixels[size_t(k)] = decode(pixels[size_t(k)]);
}

// The two passes of a separable resize of `src` (w x h, C channels) to W x H: every input
// row to the new width into rows of type Row, then the columns; each output is its own sum
// in tap order, so the threads do not change the bits.
//
// Both passes walk memory in order: the row pass adds a tap's channels together (one texel
// read), the column pass adds a tap's whole input row into an output row of sums. Each sum
// still takes its terms in tap order, so the bits are those of one sum at a time (Fox's
// eval spent ~7 % of its time here with the taps read one channel or one row at a time).
template <class Row, uint32_t CC>
void separable_rows(const float* src, uint32_t w, uint32_t h, uint32_t W, const AxisTaps& tx, Row* rows) {
  constexpr uint32_t C = CC;
#pragma omp parallel for schedule(static)
  for (long j = 0; j < long(h); ++j)
    for (uint32_t i = 0; i < W; ++i) {
      const uint32_t* idx = &tx.index[size_t(i) * tx.count];
      const double* wt = &tx.weight[size_t(i) * tx.count];
      const float* row = src + size_t(j) * w * C;
      double acc[C] = {};
      for (uint32_t k = 0; k < tx.count; ++k)
        for (uint32_t c = 0; c < C; ++c) acc[c] += wt[k] * row[size_t(idx[k]) * C + c];
      for (uint32_t c = 0; c < C; ++c) rows[(size_t(j) * W + i) * C + c] = Row(acc[c]);
    }
}

template <class Row>
Image separable(const float* src, uint32_t w, uint32_t h, uint32_t C, uint32_t W, uint32_t H, const AxisTaps& tx,
                const AxisTaps& ty, uint32_t bits) {
  std::vector<Row> rows(size_t(h) * W * C);
  switch (C) {
    case 1: separable_rows<Row, 1>(src, w, h, W, tx, rows.data()); break;
    case 2: separable_rows<Row, 2>(src, w, h, W, tx, rows.data()); break;
    case 3: separable_rows<Row, 3>(src, w, h, W, tx, rows.data()); break;
    case 4: separable_rows<Row, 4>(src, w, h, W, tx, rows.data()); break;
    default: throw std::runtime_error("resize: " + std::to_string(C) + " channels");
  }
  Image out;
  out.width = W, out.height = H, out.channels = C, out.bits = bits;
  out.pixels.resize(size_t(W) * H * C);
  const size_t n = size_t(W) * C;  // values a row
#pragma omp parallel
  {
    std::vector<double> acc(n);
#pragma omp for schedule(static)
    for (long j = 0; j < long(H); ++j) {
      const uint32_t* idx = &ty.index[size_t(j) * ty.count];
      const double* wt = &ty.weight[size_t(j) * ty.count];
      std::fill(acc.begin(), acc.end(), 0.0);
      for (uint32_t k = 0; k < ty.count; ++k) {
        const Row* in = &rows[size_t(idx[k]) * n];
        const double wk = wt[k];
        for (size_t e = 0; e < n; ++e) acc[e] += wk * double(in[e]);
      }
      float* o = &out.pixels[size_t(j) * n];
      for (size_t e = 0; e < n; ++e) o[e] = float(acc[e]);
    }
  }
  return out;
}

}  // namespace

Image resize_area(const Image& in, uint32_t W, uint32_t H) {
  if (W == in.width && H == in.height) return in;
  // Rows kept in double: the box keeps the mean exactly.
  return separable<double>(in.pixels.data(), in.width, in.height, in.channels, W, H, area_taps(in.width, W),
                           area_taps(in.height, H), in.bits);
}

Image resize_lanczos3(const Image& in, uint32_t W, uint32_t H, bool linear_light) {
  if (W == in.width && H == in.height) return in;
  if (W == 0 || H == 0 || in.width == 0 || in.height == 0 || in.channels == 0)
    throw std::runtime_error("resize_lanczos3: empty image or size");
  const uint32_t C = in.channels;
  // Stored values are read in place; linear light decodes a copy.
  std::vector<float> decoded;
  if (linear_light) {
    decoded = in.pixels;
    decode_colour(decoded, C);
  }
  const float* src = linear_light ? decoded.data() : in.pixels.data();
  Image out = separable<float>(src, in.width, in.height, C, W, H, lanczos3_taps(in.width, W), lanczos3_taps(in.height, H),
                               in.bits);
#pragma omp parallel for schedule(static) if (worth_threads(long(out.pixels.size())))
  for (long k = 0; k < long(out.pixels.size()); ++k) {
    float v = std::clamp(out.pixels[size_t(k)], 0.0f, 1.0f);  // Lanczos rings past the range at edges
    if (linear_light && is_colour(uint32_t(size_t(k) % C), C)) v = encode(v);
    out.pixels[size_t(k)] = v;
  }
  return out;
}

std::vector<Image> mip_chain(const Image& image, uint32_t levels, bool colour) {
  std::vector<Image> chain;
  if (levels == 0) return chain;
  chain.push_back(image);
  if (levels == 1) return chain;
  const uint32_t C = image.channels;
  Image linear = image;
  if (colour) decode_colour(linear.pixels, C);
  for (uint32_t l = 1; l < levels; ++l) {
    // From the level above, as glGenerateMipmap does: a quarter of the work of filtering
    // level 0 each time, the same 2 x 2 box for even sides.
    linear = resize_area(linear, std::max(1u, image.width >> l), std::max(1u, image.height >> l));
    Image level = linear;
    if (colour) {
#pragma omp parallel for schedule(static) if (worth_threads(long(level.pixels.size())))
      for (long k = 0; k < long(level.pixels.size()); ++k)
        if (is_colour(uint32_t(size_t(k) % C), C)) level.pixels[size_t(k)] = encode(level.pixels[size_t(k)]);
    }
    chain.push_back(std::move(level));
  }
  return chain;
}

}  // namespace uvpress::eval
