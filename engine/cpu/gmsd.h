// GMSD exactly as reference/gmsd.md (Xue et al. 2014, the authors' MATLAB definition on
// float luminance): 2x2 mean with stride 2 and zero padding, Prewitt/3 with zero padding,
// GMS with T = 170/255^2, population standard deviation divided by N - 1.
// Real = double is the golden-vector reference; Real = float mirrors gmsd.glsl term by
// term (same order of operations) so the two backends round alike.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "engine.h"

namespace uvpress::engine::cpu {

template <class Real>
Real gmsd(const Real* a, const Real* b, uint32_t width, uint32_t height) {
  const uint32_t w = (width + 1) / 2, h = (height + 1) / 2;
  const size_t n = size_t(w) * h;
  if (n < 2) return Real(0);
  // Every element is written before it is read. The buffers are the thread's own and kept
  // from call to call: fresh ones for eval's 1696-px views were mapped and page-faulted
  // anew on every call, a third of the time of this function; not zeroed when they grow.
  thread_local UninitializedVector<Real> scratch;
  if (scratch.size() < 3 * n) scratch.resize(3 * n);
  Real* const d1 = scratch.data();
  Real* const d2 = d1 + n;
  Real* const gms = d2 + n;
  auto y = [&](const Real* img, uint32_t x, uint32_t yy) {
    return (x < width && yy < height) ? img[size_t(yy) * width + x] : Real(0);
  };
  auto mean4 = [&](const Real* img, uint32_t i, uint32_t j) {
    Real s = y(img, 2 * i, 2 * j) + y(img, 2 * i + 1, 2 * j);
    s += y(img, 2 * i, 2 * j + 1);
    s += y(img, 2 * i + 1, 2 * j + 1);
    return Real(0.25) * s;
  };
  // The 2 x 2 blocks wholly inside the image first, without bounds checks, so that the
  // compiler runs them in vector lanes (the same operations in the same order per element:
  // the same bits as the checked form, which takes the last row and column of odd sizes).
  const uint32_t wf = width / 2, hf = height / 2;
  for (uint32_t j = 0; j < h; ++j) {
    Real* o1 = &d1[size_t(j) * w];
    Real* o2 = &d2[size_t(j) * w];
    uint32_t i0 = 0;
    if (j < hf) {
      const Real *a0 = a + size_t(2 * j) * width, *a1 = a0 + width, *b0 = b + size_t(2 * j) * width, *b1 = b0 + width;
      for (uint32_t i = 0; i < wf; ++i) {
        Real s1 = a0[2 * i] + a0[2 * i + 1];
        s1 += a1[2 * i];
        s1 += a1[2 * i + 1];
        Real s2 = b0[2 * i] + b0[2 * i + 1];
        s2 += b1[2 * i];
        s2 += b1[2 * i + 1];
        o1[i] = Real(0.25) * s1;
        o2[i] = Real(0.25) * s2;
      }
      i0 = wf;
    }
    for (uint32_t i = i0; i < w; ++i) o1[i] = mean4(a, i, j), o2[i] = mean4(b, i, j);
  }
  const Real T = Real(170.0 / (255.0 * 255.0)), third = Real(1) / Real(3);
  // Prewitt/3 magnitude at (i, j) from the three rows around it (up, mid, down: rows j - 1,
  // j, j + 1, with the zero padding already in whatever the caller passes at the borders).
  auto magnitude = [&](Real ul, Real um, Real ur, Real ml, Real mr, Real dl, Real dm, Real dr) {
    // Columns i-1 and i+1 of rows j-1..j+1 (x along a row), and the transpose.
    Real gx = (ur + mr) + dr;
    gx -= (ul + ml) + dl;
    Real gy = (dl + dm) + dr;
    gy -= (ul + um) + ur;
    gx *= third, gy *= third;
    Real m2 = gx * gx;
    m2 += gy * gy;
    return std::sqrt(m2);
  };
  auto similarity = [&](Real g1, Real g2) {
    Real num = Real(2) * g1 * g2;
    num += T;
    Real den = g1 * g1;
    den += g2 * g2;
    den += T;
    return num / den;
  };
  auto checked = [&](const Real* d, int i, int j) {
    auto at = [&](int x, int yy) {
      return (x >= 0 && yy >= 0 && x < int(w) && yy < int(h)) ? d[size_t(yy) * w + size_t(x)] : Real(0);
    };
    return magnitude(at(i - 1, j - 1), at(i, j - 1), at(i + 1, j - 1), at(i - 1, j), at(i + 1, j), at(i - 1, j + 1),
                     at(i, j + 1), at(i + 1, j + 1));
  };
  // Interior texels unchecked (vector lanes), the one-texel frame checked; then the sum in
  // row-major order, one addition after another as before.
  for (uint32_t j = 0; j < h; ++j) {
    Real* g = &gms[size_t(j) * w];
    const bool inner_row = j > 0 && j + 1 < h;
    if (inner_row && w > 2) {
      const Real *p1 = &d1[size_t(j) * w], *u1 = p1 - w, *n1 = p1 + w;
      const Real *p2 = &d2[size_t(j) * w], *u2 = p2 - w, *n2 = p2 + w;
      for (uint32_t i = 1; i + 1 < w; ++i) {
        const Real g1 = magnitude(u1[i - 1], u1[i], u1[i + 1], p1[i - 1], p1[i + 1], n1[i - 1], n1[i], n1[i + 1]);
        const Real g2 = magnitude(u2[i - 1], u2[i], u2[i + 1], p2[i - 1], p2[i + 1], n2[i - 1], n2[i], n2[i + 1]);
        g[i] = similarity(g1, g2);
      }
      g[0] = similarity(checked(d1, 0, int(j)), checked(d2, 0, int(j)));
      g[w - 1] = similarity(checked(d1, int(w - 1), int(j)), checked(d2, int(w - 1), int(j)));
    } else {
      for (uint32_t i = 0; i < w; ++i) g[i] = similarity(checked(d1, int(i), int(j)), checked(d2, int(i), int(j)));
    }
  }
  Real sum = 0;
  for (size_t k = 0; k < n; ++k) sum += gms[k];
  const Real mean = sum / Real(n);
  Real var = 0;
  for (size_t k = 0; k < n; ++k) {
    Real d = gms[k] - mean;
    var += d * d;
  }
  return std::sqrt(var / Real(n - 1));
}

}  // namespace uvpress::engine::cpu
