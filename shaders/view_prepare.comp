#version 450
// Per-triangle views, once per view (seed 001, section 4.1.1): coverage of the triangle
// and its one-ring, and the reference render: bilinear, clamp-to-edge samples of the
// source luminance. One workgroup per view; engine/cpu/view_raster.cpp is the oracle.
#extension GL_GOOGLE_include_directive : require
#include "layout.h"
#include "view_raster.glsl"

layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Views { ViewDesc views[]; };
layout(std430, binding = 1) readonly buffer Triangles { ViewTriangle triangles[]; };
layout(std430, binding = 2) readonly buffer Texture { float texels[]; };
layout(std430, binding = 3) writeonly buffer Coverage { uint coverage[]; };   // 4 pixels a word, page-relative
layout(std430, binding = 4) writeonly buffer Reference { float reference[]; }; // page-relative
layout(push_constant) uniform Push { ViewPush p; };

shared ivec2 s_v[kViewMaxTriangles][3];  // snapped, positively oriented
shared ivec4 s_box[kViewMaxTriangles];   // pixel range i_lo, i_hi, j_lo, j_hi (empty when lo > hi)
shared bvec3 s_own[kViewMaxTriangles];
shared vec3 s_depth[kViewMaxTriangles];

float texel(int i, int j) { return texels[uint(j) * p.texture_width + uint(i)]; }

float bilinear_clamped(float s, float t) {
  s = min(max(s, 0.0), float(p.texture_width - 1u));
  t = min(max(t, 0.0), float(p.texture_height - 1u));
  float fs0 = floor(s), ft0 = floor(t);
  int i0 = int(fs0), j0 = int(ft0);
  int i1 = min(i0 + 1, int(p.texture_width) - 1), j1 = min(j0 + 1, int(p.texture_height) - 1);
  float fs = s - fs0, ft = t - ft0;
  precise float top = (1.0 - fs) * texel(i0, j0);
  top += fs * texel(i1, j0);
  precise float bottom = (1.0 - fs) * texel(i0, j1);
  bottom += fs * texel(i1, j1);
  precise float v = (1.0 - ft) * top;
  v += ft * bottom;
  return v;
}

void main() {
  uint view_index = p.first + gl_WorkGroupID.x;
  uint local_view = view_index - p.view_base;  // outputs are page-relative
  ViewDesc view = views[view_index];
  uint tid = gl_LocalInvocationIndex;
  int S = int(p.size);
  if (tid < view.triangle_count) {
    ViewTriangle t = triangles[view.first_triangle + tid];
    ivec2 a = ivec2(snap16(t.xy[0]), snap16(t.xy[1]));
    ivec2 b = ivec2(snap16(t.xy[2]), snap16(t.xy[3]));
    ivec2 c = ivec2(snap16(t.xy[4]), snap16(t.xy[5]));
    int area = edge_function(a, b, c);
    if (area < 0) { ivec2 tmp = b; b = c; c = tmp; }
    s_v[tid][0] = a; s_v[tid][1] = b; s_v[tid][2] = c;
    ivec2 lo = min(min(a, b), c), hi = max(max(a, b), c);
    ivec4 box = ivec4(max(0, (lo.x - 8 + 15) >> 4), min(S - 1, (hi.x - 8) >> 4),
                      max(0, (lo.y - 8 + 15) >> 4), min(S - 1, (hi.y - 8) >> 4));
    if (area == 0) box = ivec4(1, 0, 1, 0);
    s_box[tid] = box;
    s_own[tid] = bvec3(owns_edge(b, c), owns_edge(c, a), owns_edge(a, b));
    s_depth[tid] = vec3(t.depth[0], t.depth[1], t.depth[2]);
  }
  barrier();

  uint words = uint(S * S) / 4u;
  for (uint w = tid; w < words; w += 256u) {
    uint packed = 0u;
    for (uint q = 0u; q < 4u; ++q) {
      uint pix = 4u * w + q;
      int i = int(pix) % S, j = int(pix) / S;
      ivec2 pc = ivec2(16 * i + 8, 16 * j + 8);
      float cx = float(i) + 0.5, cy = float(j) + 0.5;
      uint best = kNoTriangle;
      float best_z = 0.0;
      for (uint k = 0u; k < view.triangle_count; ++k) {
        ivec4 box = s_box[k];
        if (i < box.x || i > box.y || j < box.z || j > box.w) continue;
        int e0 = edge_function(s_v[k][1], s_v[k][2], pc);
        int e1 = edge_function(s_v[k][2], s_v[k][0], pc);
        int e2 = edge_function(s_v[k][0], s_v[k][1], pc);
        bvec3 own = s_own[k];
        if (e0 < 0 || e1 < 0 || e2 < 0 || (e0 == 0 && !own.x) || (e1 == 0 && !own.y) || (e2 == 0 && !own.z)) continue;
        float z = plane_at(s_depth[k].x, s_depth[k].y, s_depth[k].z, cx, cy);
        if (best == kNoTriangle || z > best_z) { best = k; best_z = z; }
      }
      packed |= best << (8u * q);
      float value = 0.0;
      if (best != kNoTriangle) {
        ViewTriangle t = triangles[view.first_triangle + best];
        float s = plane_at(t.s[0], t.s[1], t.s[2], cx, cy);
        float tt = plane_at(t.t[0], t.t[1], t.t[2], cx, cy);
        value = bilinear_clamped(s, tt);
      }
      reference[local_view * uint(S * S) + pix] = value;
    }
    coverage[local_view * uint(S * S) / 4u + w] = packed;
  }
}
