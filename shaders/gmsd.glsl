// GMSD for one image pair per workgroup of 256 invocations, term for term as
// engine/cpu/gmsd.h (Real = float). Images up to 64 x 64. The including shader defines
//   float gmsd_a(int x, int y);  float gmsd_b(int x, int y);
// returning 0 outside the image. Sums are fixed-order trees: deterministic per device.
#ifndef UVPRESS_GMSD_GLSL
#define UVPRESS_GMSD_GLSL

#define GMSD_WG 256u

shared float s_d1[1024];
shared float s_d2[1024];
shared float s_gms[1024];
shared float s_red[GMSD_WG];

float gmsd_a(int x, int y);
float gmsd_b(int x, int y);

// Sum of v over the workgroup; every invocation must call it (uniform control flow).
float workgroup_sum(float v) {
  uint tid = gl_LocalInvocationIndex;
  s_red[tid] = v;
  barrier();
  for (uint s = GMSD_WG / 2u; s > 0u; s >>= 1u) {
    if (tid < s) s_red[tid] += s_red[tid + s];
    barrier();
  }
  float r = s_red[0];
  barrier();
  return r;
}

float gmsd_d(uint which, int x, int y, int w, int h) {
  if (x < 0 || y < 0 || x >= w || y >= h) return 0.0;
  return which == 0u ? s_d1[y * w + x] : s_d2[y * w + x];
}

float gmsd_magnitude(uint which, int i, int j, int w, int h) {
  precise float gx = (gmsd_d(which, i + 1, j - 1, w, h) + gmsd_d(which, i + 1, j, w, h)) + gmsd_d(which, i + 1, j + 1, w, h);
  gx -= (gmsd_d(which, i - 1, j - 1, w, h) + gmsd_d(which, i - 1, j, w, h)) + gmsd_d(which, i - 1, j + 1, w, h);
  precise float gy = (gmsd_d(which, i - 1, j + 1, w, h) + gmsd_d(which, i, j + 1, w, h)) + gmsd_d(which, i + 1, j + 1, w, h);
  gy -= (gmsd_d(which, i - 1, j - 1, w, h) + gmsd_d(which, i, j - 1, w, h)) + gmsd_d(which, i + 1, j - 1, w, h);
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
  for (uint k = tid; k < n; k += GMSD_WG) {
    int i = int(k) % w, j = int(k) / w;
    precise float s1 = gmsd_a(2 * i, 2 * j) + gmsd_a(2 * i + 1, 2 * j);
    s1 += gmsd_a(2 * i, 2 * j + 1);
    s1 += gmsd_a(2 * i + 1, 2 * j + 1);
    precise float s2 = gmsd_b(2 * i, 2 * j) + gmsd_b(2 * i + 1, 2 * j);
    s2 += gmsd_b(2 * i, 2 * j + 1);
    s2 += gmsd_b(2 * i + 1, 2 * j + 1);
    s_d1[k] = 0.25 * s1;
    s_d2[k] = 0.25 * s2;
  }
  barrier();
  const float T = 170.0 / (255.0 * 255.0);
  precise float part = 0.0;
  for (uint k = tid; k < n; k += GMSD_WG) {
    int i = int(k) % w, j = int(k) / w;
    float g1 = gmsd_magnitude(0u, i, j, w, h), g2 = gmsd_magnitude(1u, i, j, w, h);
    precise float num = 2.0 * g1 * g2;
    num += T;
    precise float den = g1 * g1;
    den += g2 * g2;
    den += T;
    float v = num / den;
    s_gms[k] = v;
    part += v;
  }
  float mean = workgroup_sum(part) / float(n);
  precise float var = 0.0;
  for (uint k = tid; k < n; k += GMSD_WG) {
    float d = s_gms[k] - mean;
    var += d * d;
  }
  float total = workgroup_sum(var);
  return n < 2u ? 0.0 : sqrt(total / float(n - 1u));
}

#endif
