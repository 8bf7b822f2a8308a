#version 450
// Re-bake sampling (engine::RebakeTexelsDesc): one 16 x 16 workgroup per tile of the new
// image, one invocation per texel. The host picked every texel's owner; this kernel filters
// the owner's footprint: ns_x by ns_y samples on a regular grid inside the texel, each
// mapped to the source by the triangle that contains it (the owner; else the first other
// entry of the tile's list that contains it; else the owner's closest point), sampled
// bilinearly by hand and averaged with equal weights. engine/cpu/rebake_texels.cpp is the
// oracle (double); here everything is fp32, relative to the texel's corner, with the
// corner's terms exact (RebakeEntry), so positions keep ~1e-7 texel precision whatever
// the triangle and image sizes.
#extension GL_GOOGLE_include_directive : require
#include "layout.h"

layout(local_size_x = 16, local_size_y = 16) in;
// The working source, split by texel index over four buffers (the device's buffer limit).
layout(std430, binding = 0) readonly buffer Source0 { float s0[]; };
layout(std430, binding = 1) readonly buffer Source1 { float s1[]; };
layout(std430, binding = 2) readonly buffer Source2 { float s2[]; };
layout(std430, binding = 3) readonly buffer Source3 { float s3[]; };
layout(std430, binding = 4) readonly buffer Entries { RebakeEntry entries[]; };  // from entry_base
layout(std430, binding = 5) readonly buffer TileStart { uint tile_start[]; };    // every tile, + 1
layout(std430, binding = 6) readonly buffer Owner { uint owner[]; };             // rows of the chunk
layout(std430, binding = 7) writeonly buffer Texels { float texels[]; };        // rows of the chunk
layout(push_constant) uniform Push { RebakePush p; };

const uint kNoOwner = 0xffffffffu;

// Edge e of entry k at the point d away from the integer tile point `corner`: signed
// distance (inside >= 0) and the offsets along the edge from its two ends. The terms with
// the corner are exact (hi parts on a 2^-12 grid times integers below 16).
void edge_at(uint k, int e, vec2 corner, vec2 d, out float dist, out float from_a, out float from_b, out vec2 u,
             out vec2 n) {
  float sg = entries[k].sign;
  vec2 uh = vec2(entries[k].uh[2 * e], entries[k].uh[2 * e + 1]);
  vec2 ul = vec2(entries[k].ul[2 * e], entries[k].ul[2 * e + 1]);
  u = uh + ul;
  n = sg * vec2(-u.y, u.x);
  precise float gh = uh.x * corner.y - uh.y * corner.x;
  gh = sg * gh - entries[k].ch[e];
  precise float gl = ul.x * corner.y - ul.y * corner.x;
  gl = sg * gl - entries[k].cl[e];
  precise float nd = n.x * d.x + n.y * d.y;
  dist = (gh + gl) + nd;
  precise float ah = uh.x * corner.x + uh.y * corner.y;
  precise float al = ul.x * corner.x + ul.y * corner.y;
  precise float ud = u.x * d.x + u.y * d.y;
  precise float fa = (ah - entries[k].s0h[e]) + (al - entries[k].s0l[e]);
  from_a = fa + ud;
  precise float fb = (ah - entries[k].s1h[e]) + (al - entries[k].s1l[e]);
  from_b = fb + ud;
}

bool inside(uint k, vec2 corner, vec2 d) {
  for (int e = 0; e < 3; ++e) {
    float dist, fa, fb;
    vec2 u, n;
    edge_at(k, e, corner, d, dist, fa, fb, u, n);
    if (dist < 0.0) return false;
  }
  return true;
}

// The closest point of entry k's triangle to corner + d (outside it), as an offset from
// `corner`: the nearest of the closest points of its edges (first on ties).
vec2 closest(uint k, vec2 corner, vec2 d) {
  float best = 0.0;
  vec2 r = d;
  for (int e = 0; e < 3; ++e) {
    float dist, fa, fb;
    vec2 u, n;
    edge_at(k, e, corner, d, dist, fa, fb, u, n);
    float slide = fa < 0.0 ? -fa : (fb > 0.0 ? -fb : 0.0);
    precise vec2 c = d - dist * n;
    c += slide * u;
    precise vec2 v = d - c;
    precise float dd = v.x * v.x + v.y * v.y;
    if (e == 0 || dd < best) {
      best = dd;
      r = c;
    }
  }
  return r;
}

int positive_mod(int i, int n) { return i >= 0 ? i % n : n - 1 - ((-i - 1) % n); }

int wrap(int i, int n, uint mode) {
  if (mode == 1u) return clamp(i, 0, n - 1);
  if (mode == 2u) {
    int m = positive_mod(i, 2 * n);
    return m < n ? m : 2 * n - 1 - m;
  }
  return positive_mod(i, n);
}

vec4 fetch(int x, int y) {
  uint k = uint(y) * p.source_width + uint(x);
  uint b = k / p.source_split;
  uint base = (k - b * p.source_split) * p.channels;
  vec4 v = vec4(0.0);
  for (uint c = 0u; c < p.channels; ++c) {
    float f;
    if (b == 0u) f = s0[base + c];
    else if (b == 1u) f = s1[base + c];
    else if (b == 2u) f = s2[base + c];
    else f = s3[base + c];
    v[c] = f;
  }
  return v;
}

// Entry k's map at the integer tile point (lx, ly): an integer part and a fraction. jh
// times a small integer is exact, so the fraction keeps ~1e-7 texel precision however far
// the source position is from the tile's.
vec2 corner_of(uint k, float lx, float ly, out ivec2 ci) {
  precise float bx = entries[k].jh[0] * lx;
  bx += entries[k].jh[1] * ly;
  precise float by = entries[k].jh[2] * lx;
  by += entries[k].jh[3] * ly;
  float ix = floor(bx), iy = floor(by);
  precise float rx = entries[k].jl[0] * lx;
  rx += entries[k].jl[1] * ly;
  precise float ry = entries[k].jl[2] * lx;
  ry += entries[k].jl[3] * ly;
  precise float fx = (bx - ix) + entries[k].of[0];
  fx += rx;
  precise float fy = (by - iy) + entries[k].of[1];
  fy += ry;
  ci = ivec2(entries[k].oi[0] + int(ix), entries[k].oi[1] + int(iy));
  return vec2(fx, fy);
}

// Bilinear sample of the source at the image, under entry k's map, of the point d away from
// the tile point `corner`; `straight`: colour divided by each texel's alpha (the last channel).
vec4 sample_at(uint k, vec2 corner, vec2 d, bool straight) {
  ivec2 ci;
  vec2 f = corner_of(k, corner.x, corner.y, ci);
  precise float j0 = entries[k].jh[0] + entries[k].jl[0], j1 = entries[k].jh[1] + entries[k].jl[1];
  precise float j2 = entries[k].jh[2] + entries[k].jl[2], j3 = entries[k].jh[3] + entries[k].jl[3];
  precise float ox = f.x + j0 * d.x;
  ox += j1 * d.y;
  ox -= 0.5;
  precise float oy = f.y + j2 * d.x;
  oy += j3 * d.y;
  oy -= 0.5;
  float fx = floor(ox), fy = floor(oy);
  precise float wx = ox - fx, wy = oy - fy;
  int ix = ci.x + int(fx), iy = ci.y + int(fy);
  int SW = int(p.source_width), SH = int(p.source_height);
  int x0 = wrap(ix, SW, p.wrap_s), x1 = wrap(ix + 1, SW, p.wrap_s);
  int y0 = wrap(iy, SH, p.wrap_t), y1 = wrap(iy + 1, SH, p.wrap_t);
  vec4 t[4] = vec4[4](fetch(x0, y0), fetch(x1, y0), fetch(x0, y1), fetch(x1, y1));
  precise float w[4] = float[4]((1.0 - wx) * (1.0 - wy), wx * (1.0 - wy), (1.0 - wx) * wy, wx * wy);
  uint alpha = p.channels - 1u;
  precise vec4 sum = vec4(0.0);
  for (int i = 0; i < 4; ++i) {
    vec4 v = t[i];
    if (straight) {
      float a = v[alpha];
      v = a > 0.0 ? v / a : vec4(0.0);
    }
    sum += w[i] * v;
  }
  return sum;
}

// Sum of the footprint's samples (see the header); `corner` is the texel's tile point.
vec4 footprint(uint own, uint first, uint last, vec2 corner, uint nsx, uint nsy, bool straight) {
  precise vec4 acc = vec4(0.0);
  for (uint j = 0u; j < nsy; ++j) {
    precise vec4 row = vec4(0.0);
    for (uint i = 0u; i < nsx; ++i) {
      vec2 d = vec2((float(i) + 0.5) / float(nsx), (float(j) + 0.5) / float(nsy));
      uint st = own;
      if (!inside(own, corner, d)) {
        bool found = false;
        for (uint k = first; k < last; ++k) {
          if (k == own || !inside(k, corner, d)) continue;
          st = k;
          found = true;
          break;
        }
        if (!found) d = closest(own, corner, d);
      }
      row += sample_at(st, corner, d, straight);
    }
    acc += row;
  }
  return acc;
}

void main() {
  uint tile_x = gl_WorkGroupID.x, tile_y = p.tile_row0 + gl_WorkGroupID.y;
  uint x = tile_x * kRebakeTile + gl_LocalInvocationID.x, y = tile_y * kRebakeTile + gl_LocalInvocationID.y;
  if (x >= p.width || y >= p.height) return;
  uint pix = (y - p.chunk_row0 * kRebakeTile) * p.width + x;
  uint C = p.channels;
  uint o = owner[pix];
  if (o == kNoOwner) {
    for (uint c = 0u; c < C; ++c) texels[pix * C + c] = 0.0;
    return;
  }
  uint tile = tile_y * p.tiles_x + tile_x;
  uint first = tile_start[tile] - p.entry_base, last = tile_start[tile + 1u] - p.entry_base;
  uint own = o - p.entry_base;
  uint nsx = entries[own].ns & 0xffffu, nsy = entries[own].ns >> 16;
  vec2 corner = vec2(float(gl_LocalInvocationID.x), float(gl_LocalInvocationID.y));
  float inv = 1.0 / float(nsx * nsy);
  vec4 acc = footprint(own, first, last, corner, nsx, nsy, false);
  if (p.premultiplied != 0u) {
    uint alpha = C - 1u;
    float a = acc[alpha] * inv;
    vec4 straight = vec4(0.0);
    if (!(a > 1e-7)) straight = footprint(own, first, last, corner, nsx, nsy, true);
    for (uint c = 0u; c < alpha; ++c) texels[pix * C + c] = a > 1e-7 ? acc[c] * inv / a : straight[c] * inv;
    texels[pix * C + alpha] = a;
  } else {
    for (uint c = 0u; c < C; ++c) texels[pix * C + c] = acc[c] * inv;
  }
}
