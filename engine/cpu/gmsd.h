// GMSD exactly as reference/gmsd.md (Xue et al. 2014, the authors' MATLAB definition on
// float luminance): 2x2 mean with stride 2 and zero padding, Prewitt/3 with zero padding,
// GMS with T = 170/255^2, population standard deviation divided by N - 1.
// Real = double is the golden-vector reference; Real = float mirrors gmsd.glsl term by
// term (same order of operations) so the two backends round alike, but for the two sums,
// which each side adds in a fixed order of its own (gmsd_sum here, workgroup lanes there).
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "engine.h"

namespace uvpress::engine::cpu {

// The stages of gmsd() below, each a pure function per element (so that any split of them
// gives the same bits): the 2 x 2 mean, stride 2 with zero padding, of img (width x height)
// into d ((width + 1) / 2 x (height + 1) / 2).
template <class Real>
void gmsd_downsample(const Real* img, uint32_t width, uint32_t height, Real* d) {
  const uint32_t w = (width + 1) / 2, h = (height + 1) / 2;
  auto y = [&](uint32_t x, uint32_t yy) { return (x < width && yy < height) ? img[size_t(yy) * width + x] : Real(0); };
  // The 2 x 2 blocks wholly inside the image first, without bounds checks, so that the
  // compiler runs them in vector lanes (the same operations in the same order per element:
  // the same bits as the checked form, which takes the last row and column of odd sizes).
  const uint32_t wf = width / 2, hf = height / 2;
  for (uint32_t j = 0; j < h; ++j) {
    Real* o = &d[size_t(j) * w];
    uint32_t i0 = 0;
    if (j < hf) {
      const Real *a0 = img + size_t(2 * j) * width, *a1 = a0 + width;
      for (uint32_t i = 0; i < wf; ++i) {
        Real s = a0[2 * i] + a0[2 * i + 1];
        s += a1[2 * i];
        s += a1[2 * i + 1];
        o[i] = Real(0.25) * s;
      }
      i0 = wf;
    }
    for (uint32_t i = i0; i < w; ++i) {
      Real s = y(2 * i, 2 * j) + y(2 * i + 1, 2 * j);
      s += y(2 * i, 2 * j + 1);
      s += y(2 * i + 1, 2 * j + 1);
      o[i] = Real(0.25) * s;
    }
  }
}

// The Prewitt/3 gradient magnitude of d (w x h, zero padding) into g.
template <class Real>
void gmsd_magnitude(const Real* d, uint32_t w, uint32_t h, Real* g) {
  const Real third = Real(1) / Real(3);
  // At (i, j) from the three rows around it (up, mid, down: rows j - 1, j, j + 1).
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
  auto checked = [&](int i, int j) {
    auto at = [&](int x, int yy) {
      return (x >= 0 && yy >= 0 && x < int(w) && yy < int(h)) ? d[size_t(yy) * w + size_t(x)] : Real(0);
    };
    return magnitude(at(i - 1, j - 1), at(i, j - 1), at(i + 1, j - 1), at(i - 1, j), at(i + 1, j), at(i - 1, j + 1),
                     at(i, j + 1), at(i + 1, j + 1));
  };
  // Interior texels unchecked (vector lanes), the one-texel frame checked.
  for (uint32_t j = 0; j < h; ++j) {
    Real* o = &g[size_t(j) * w];
    if (j > 0 && j + 1 < h && w > 2) {
      const Real *p = &d[size_t(j) * w], *u = p - w, *n = p + w;
      for (uint32_t i = 1; i + 1 < w; ++i)
        o[i] = magnitude(u[i - 1], u[i], u[i + 1], p[i - 1], p[i + 1], n[i - 1], n[i], n[i + 1]);
      o[0] = checked(0, int(j)), o[w - 1] = checked(int(w - 1), int(j));
    } else {
      for (uint32_t i = 0; i < w; ++i) o[i] = checked(int(i), int(j));
    }
  }
}

// The sum of term(0..n). Up to kGmsdSerialTerms terms (the per-triangle views' maps, 32 x
// 32 at most) one after another, in order, as they always were: the triangle stage's
// searches follow the last bits of every score (in lanes, its layouts took other paths and
// `bench quality` ratios moved by up to 0.1). More (eval's views) in kGmsdLanes interleaved
// partial sums (term k to lane k mod kGmsdLanes, each lane in order), the lanes then added
// pairwise in a fixed order: the same bits on any machine, no addition waiting on the last
// (Fox's eval spent 1.2 s in GMSD with one chain, 0.8 s in lanes), and nearer the exact sum
// than one long chain (tests/engine/test_gmsd.cpp).
constexpr size_t kGmsdLanes = 16, kGmsdSerialTerms = 4096;
template <class Real, class Term>
Real gmsd_sum(size_t n, Term&& term) {
  if (n <= kGmsdSerialTerms) {
    Real sum = 0;
    for (size_t k = 0; k < n; ++k) sum += term(k);
    return sum;
  }
  Real part[kGmsdLanes] = {};
  size_t k = 0;
  for (; k + kGmsdLanes <= n; k += kGmsdLanes)
    for (size_t l = 0; l < kGmsdLanes; ++l) part[l] += term(k + l);
  for (; k < n; ++k) part[k % kGmsdLanes] += term(k);
  for (size_t half = kGmsdLanes / 2; half > 0; half /= 2)
    for (size_t l = 0; l < half; ++l) part[l] += part[l + half];
  return part[0];
}

// The gradient magnitude similarity of g1 and g2 (n each, T = 170/255^2) into gms, and its
// population standard deviation divided by n - 1 (the sums by gmsd_sum).
template <class Real>
Real gmsd_deviation(const Real* g1, const Real* g2, size_t n, Real* gms) {
  const Real T = Real(170.0 / (255.0 * 255.0));
  for (size_t k = 0; k < n; ++k) {
    Real num = Real(2) * g1[k] * g2[k];
    num += T;
    Real den = g1[k] * g1[k];
    den += g2[k] * g2[k];
    den += T;
    gms[k] = num / den;
  }
  const Real mean = gmsd_sum<Real>(n, [&](size_t k) { return gms[k]; }) / Real(n);
  const Real var = gmsd_sum<Real>(n, [&](size_t k) {
    Real d = gms[k] - mean;
    return d * d;
  });
  return std::sqrt(var / Real(n - 1));
}

// The thread's own scratch for the stages (Slot: buffers in use at once), kept from call to
// call: fresh buffers for eval's 1696-px views were mapped and page-faulted anew on every
// call, a third of the time of gmsd(); not zeroed when they grow (every element is written
// before it is read).
template <class Real, int Slot>
Real* gmsd_scratch(size_t count) {
  thread_local UninitializedVector<Real> scratch;
  if (scratch.size() < count) scratch.resize(count);
  return scratch.data();
}

// The reference side of gmsd(a, ., width, height) on its own: a's gradient magnitudes
// (Engine::gmsd_half_size(width, height) elements) into g1.
template <class Real>
void gmsd_reference(const Real* a, uint32_t width, uint32_t height, Real* g1) {
  const uint32_t w = (width + 1) / 2, h = (height + 1) / 2;
  Real* const d = gmsd_scratch<Real, 0>(size_t(w) * h);
  gmsd_downsample(a, width, height, d);
  gmsd_magnitude(d, w, h, g1);
}

// gmsd(a, b, width, height) from a's gmsd_reference and b's gmsd_downsample (`half`), bit
// for bit.
template <class Real>
Real gmsd_against_halved(const Real* g1, const Real* half, uint32_t width, uint32_t height) {
  const uint32_t w = (width + 1) / 2, h = (height + 1) / 2;
  const size_t n = size_t(w) * h;
  if (n < 2) return Real(0);
  // Slots 0 and 1 may hold the caller's half and g1 (gmsd_against, gmsd).
  Real* const g2 = gmsd_scratch<Real, 2>(n);
  Real* const gms = gmsd_scratch<Real, 3>(n);
  gmsd_magnitude(half, w, h, g2);
  return gmsd_deviation(g1, g2, n, gms);
}

// gmsd(a, b, width, height) from a's gmsd_reference, bit for bit.
template <class Real>
Real gmsd_against(const Real* g1, const Real* b, uint32_t width, uint32_t height) {
  Real* const d = gmsd_scratch<Real, 0>(size_t((width + 1) / 2) * ((height + 1) / 2));
  gmsd_downsample(b, width, height, d);
  return gmsd_against_halved(g1, d, width, height);
}

template <class Real>
Real gmsd(const Real* a, const Real* b, uint32_t width, uint32_t height) {
  Real* const g1 = gmsd_scratch<Real, 1>(size_t((width + 1) / 2) * ((height + 1) / 2));
  gmsd_reference(a, width, height, g1);
  return gmsd_against(g1, b, width, height);
}

}  // namespace uvpress::engine::cpu
