// GMSD for one image pair per workgroup, term for term as engine/cpu/gmsd.h (Real = float).
// Images up to 64 x 64. The including shader declares its workgroup size with
// local_size_x_id = 0 (a multiple of 8, at most 1024) and defines
//   float gmsd_a(int x, int y);  float gmsd_b(int x, int y);
// for 0 <= x < width + 1, 0 <= y < height + 1, returning 0 outside the image. Sums are
// fixed-order (see wg_sum): deterministic per device and workgroup size.
#ifndef UVPRESS_GMSD_GLSL
#define UVPRESS_GMSD_GLSL

#define WG gl_WorkGroupSize.x

// Downsampled images in zero-padded tiles (a one-pixel border of zeros), so the Prewitt
// stencil reads without bounds checks or branches; the GMS map.
// An including shader may lend its own shared pool (GMSD_POOL: an array of at least
// GMSD_POOL_FLOATS floats) so the kernel's phases share one block of shared memory.
#define GMSD_PAD (34u * 34u)
#define GMSD_POOL_FLOATS (2u * GMSD_PAD + 1024u)
#ifdef GMSD_POOL
#define s_d1(i) GMSD_POOL[(i)]
#define s_d2(i) GMSD_POOL[GMSD_PAD + (i)]
#define s_gms(i) GMSD_POOL[2u * GMSD_PAD + (i)]
#else
shared float s_gmsd_pool[GMSD_POOL_FLOATS];
#define s_d1(i) s_gmsd_pool[(i)]
#define s_d2(i) s_gmsd_pool[GMSD_PAD + (i)]
#define s_gms(i) s_gmsd_pool[2u * GMSD_PAD + (i)]
#endif

// Workgroup reductions: every invocation writes its partial, the first WG/8 invocations
// each add 8 consecutive partials in order, then every invocation adds those WG/8 sums in
// order. Two barriers; the buffers alternate between calls, so back-to-back reductions
// need no trailing barrier. Every invocation must call (uniform control flow).
shared vec4 s_red[2][WG];
shared vec4 s_red8[2][WG / 8u];
uint g_red_parity = 0u;

vec4 wg_sum4(vec4 v) {
  uint tid = gl_LocalInvocationIndex, b = g_red_parity;
  g_red_parity ^= 1u;
  s_red[b][tid] = v;
  barrier();
  if (tid < WG / 8u) {
    precise vec4 s = s_red[b][8u * tid];
    for (uint k = 1u; k < 8u; ++k) s += s_red[b][8u * tid + k];
    s_red8[b][tid] = s;
  }
  barrier();
  precise vec4 s = s_red8[b][0];
  for (uint k = 1u; k < WG / 8u; ++k) s += s_red8[b][k];
  return s;
}

vec4 wg_min4(vec4 v) {
  uint tid = gl_LocalInvocationIndex, b = g_red_parity;
  g_red_parity ^= 1u;
  s_red[b][tid] = v;
  barrier();
  if (tid < WG / 8u) {
    vec4 s = s_red[b][8u * tid];
    for (uint k = 1u; k < 8u; ++k) s = min(s, s_red[b][8u * tid + k]);
    s_red8[b][tid] = s;
  }
  barrier();
  vec4 s = s_red8[b][0];
  for (uint k = 1u; k < WG / 8u; ++k) s = min(s, s_red8[b][k]);
  return s;
}

float workgroup_sum(float v) { return wg_sum4(vec4(v, 0.0, 0.0, 0.0)).x; }

float gmsd_a(int x, int y);
float gmsd_b(int x, int y);

float gmsd_magnitude(uint which, uint c, uint W2) {
  // c: the centre's index in the padded tile of row length W2.
  float a00, a10, a20, a01, a21, a02, a12, a22;
  if (which == 0u) {
    a00 = s_d1(c - W2 - 1u); a10 = s_d1(c - W2); a20 = s_d1(c - W2 + 1u);
    a01 = s_d1(c - 1u);                          a21 = s_d1(c + 1u);
    a02 = s_d1(c + W2 - 1u); a12 = s_d1(c + W2); a22 = s_d1(c + W2 + 1u);
  } else {
    a00 = s_d2(c - W2 - 1u); a10 = s_d2(c - W2); a20 = s_d2(c - W2 + 1u);
    a01 = s_d2(c - 1u);                          a21 = s_d2(c + 1u);
    a02 = s_d2(c + W2 - 1u); a12 = s_d2(c + W2); a22 = s_d2(c + W2 + 1u);
  }
  // Padding zeros stand for the CPU's out-of-range zeros: the same sums, term for term.
  precise float gx = (a20 + a21) + a22;
  gx -= (a00 + a01) + a02;
  precise float gy = (a02 + a12) + a22;
  gy -= (a00 + a10) + a20;
  const float third = 1.0 / 3.0;
  gx *= third;
  gy *= third;
  precise float m2 = gx * gx;
  m2 += gy * gy;
  return sqrt(m2);
}

float gmsd_run(uint width, uint height) {
  uint tid = gl_LocalInvocationIndex;
  int w = int((width + 1u) / 2u), h = int((height + 1u) / 2u);
  uint n = uint(w * h);
  uint W2 = uint(w) + 2u, padded = W2 * uint(h + 2);
  for (uint k = tid; k < padded; k += WG) {
    int i = int(k % W2) - 1, j = int(k / W2) - 1;
    float d1 = 0.0, d2 = 0.0;
    if (i >= 0 && j >= 0 && i < w && j < h) {
      precise float s1 = gmsd_a(2 * i, 2 * j) + gmsd_a(2 * i + 1, 2 * j);
      s1 += gmsd_a(2 * i, 2 * j + 1);
      s1 += gmsd_a(2 * i + 1, 2 * j + 1);
      precise float s2 = gmsd_b(2 * i, 2 * j) + gmsd_b(2 * i + 1, 2 * j);
      s2 += gmsd_b(2 * i, 2 * j + 1);
      s2 += gmsd_b(2 * i + 1, 2 * j + 1);
      d1 = 0.25 * s1;
      d2 = 0.25 * s2;
    }
    s_d1(k) = d1;
    s_d2(k) = d2;
  }
  barrier();
  const float T = 170.0 / (255.0 * 255.0);
  precise float part = 0.0;
  for (uint k = tid; k < n; k += WG) {
    uint c = (k / uint(w) + 1u) * W2 + k % uint(w) + 1u;
    float g1 = gmsd_magnitude(0u, c, W2), g2 = gmsd_magnitude(1u, c, W2);
    precise float num = 2.0 * g1 * g2;
    num += T;
    precise float den = g1 * g1;
    den += g2 * g2;
    den += T;
    float v = num / den;
    s_gms(k) = v;
    part += v;
  }
  float mean = workgroup_sum(part) / float(n);
  precise float var = 0.0;
  for (uint k = tid; k < n; k += WG) {
    float d = s_gms(k) - mean;
    var += d * d;
  }
  float total = workgroup_sum(var);
  return n < 2u ? 0.0 : sqrt(total / float(n - 1u));
}

#endif
