// GMSD exactly as reference/gmsd.md (Xue et al. 2014, the authors' MATLAB definition on
// float luminance): 2x2 mean with stride 2 and zero padding, Prewitt/3 with zero padding,
// GMS with T = 170/255^2, population standard deviation divided by N - 1.
// Real = double is the golden-vector reference; Real = float mirrors gmsd.glsl term by
// term (same order of operations) so the two backends round alike.
#pragma once

#include <cmath>
#include <cstdint>
#include <memory>

namespace uvpress::engine::cpu {

template <class Real>
Real gmsd(const Real* a, const Real* b, uint32_t width, uint32_t height) {
  const uint32_t w = (width + 1) / 2, h = (height + 1) / 2;
  const size_t n = size_t(w) * h;
  if (n < 2) return Real(0);
  // Every element is written before it is read, so the buffers are not zeroed (for eval's
  // 1248-px views, zeroing cost more than the arithmetic).
  const std::unique_ptr<Real[]> d1(new Real[n]), d2(new Real[n]), gms(new Real[n]);
  auto y = [&](const Real* img, uint32_t x, uint32_t yy) {
    return (x < width && yy < height) ? img[size_t(yy) * width + x] : Real(0);
  };
  for (uint32_t j = 0; j < h; ++j)
    for (uint32_t i = 0; i < w; ++i) {
      Real s1 = y(a, 2 * i, 2 * j) + y(a, 2 * i + 1, 2 * j);
      s1 += y(a, 2 * i, 2 * j + 1);
      s1 += y(a, 2 * i + 1, 2 * j + 1);
      Real s2 = y(b, 2 * i, 2 * j) + y(b, 2 * i + 1, 2 * j);
      s2 += y(b, 2 * i, 2 * j + 1);
      s2 += y(b, 2 * i + 1, 2 * j + 1);
      d1[size_t(j) * w + i] = Real(0.25) * s1;
      d2[size_t(j) * w + i] = Real(0.25) * s2;
    }
  const Real T = Real(170.0 / (255.0 * 255.0)), third = Real(1) / Real(3);
  auto magnitude = [&](const Real* d, int i, int j) {
    auto at = [&](int x, int yy) {
      return (x >= 0 && yy >= 0 && x < int(w) && yy < int(h)) ? d[size_t(yy) * w + size_t(x)] : Real(0);
    };
    // Columns j-1 and j+1 of rows i-1..i+1 (x along a row), and the transpose.
    Real gx = (at(i + 1, j - 1) + at(i + 1, j)) + at(i + 1, j + 1);
    gx -= (at(i - 1, j - 1) + at(i - 1, j)) + at(i - 1, j + 1);
    Real gy = (at(i - 1, j + 1) + at(i, j + 1)) + at(i + 1, j + 1);
    gy -= (at(i - 1, j - 1) + at(i, j - 1)) + at(i + 1, j - 1);
    gx *= third, gy *= third;
    Real m2 = gx * gx;
    m2 += gy * gy;
    return std::sqrt(m2);
  };
  Real sum = 0;
  for (uint32_t j = 0; j < h; ++j)
    for (uint32_t i = 0; i < w; ++i) {
      Real g1 = magnitude(d1.get(), int(i), int(j)), g2 = magnitude(d2.get(), int(i), int(j));
      Real num = Real(2) * g1 * g2;
      num += T;
      Real den = g1 * g1;
      den += g2 * g2;
      den += T;
      Real v = num / den;
      gms[size_t(j) * w + i] = v;
      sum += v;
    }
  const Real mean = sum / Real(n);
  Real var = 0;
  for (size_t k = 0; k < n; ++k) {
    Real d = gms[k] - mean;
    var += d * d;
  }
  return std::sqrt(var / Real(n - 1));
}

}  // namespace uvpress::engine::cpu
