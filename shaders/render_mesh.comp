#version 450
// Whole-mesh renders (eval, seed 001 section 5.1): one 16 x 16 workgroup per screen tile
// of one view, one invocation per pixel. Triangles come set up and binned by the host
// (engine/mesh_setup.cpp); every pixel walks its tile's list in increasing triangle index:
// integer edge functions with a top-left rule, depth 1/w (larger is nearer, ties keep the
// earlier triangle), perspective-correct texel coordinates and a bilinear (one level) or
// trilinear (a mip chain: level of detail from the planes' analytic derivatives) sample by hand.
// engine/cpu/render_mesh.cpp is the oracle: same operations in the same order.
#extension GL_GOOGLE_include_directive : require
#include "layout.h"

layout(local_size_x = 16, local_size_y = 16) in;
layout(std430, binding = 0) readonly buffer Triangles { MeshTriangle triangles[]; };
layout(std430, binding = 1) readonly buffer BinOffsets { uint bin_offsets[]; };  // per view and tile, + 1
layout(std430, binding = 2) readonly buffer BinItems { uint bin_items[]; };      // indices into triangles
layout(std430, binding = 3) readonly buffer Texture { float texels[]; };
layout(std430, binding = 4) writeonly buffer Coverage { uint coverage[]; };
layout(std430, binding = 5) writeonly buffer Pixels { float pixels[]; };
layout(push_constant) uniform Push { MeshPush p; };

int edge_function(int ax, int ay, int bx, int by, int px, int py) { return (bx - ax) * (py - ay) - (by - ay) * (px - ax); }

bool owns_edge(int ax, int ay, int bx, int by) {
  int dx = bx - ax, dy = by - ay;
  return dy > 0 || (dy == 0 && dx < 0);
}

float plane(float c0, float c1, float c2, float fx, float fy) {
  precise float v = c0 + c1 * fx;
  v += c2 * fy;
  return v;
}

int wrap(int i, int n) {
  int r = i % n;
  return r < 0 ? r + n : r;
}

// Level l's first texel in the texture buffer: the texels of levels 0 .. l - 1.
uint level_offset(uint level) {
  uint n = 0u;
  for (uint k = 0u; k < level; ++k) n += max(1u, p.texture_width >> k) * max(1u, p.texture_height >> k);
  return n;
}

// The bilinear sample of mip level `level` at level-0 texel coordinates (s, t), `channels`
// of it. The caller blends levels in registers and writes each pixel once: on a discrete GPU
// the pixels live in host memory (HostAccess::Read), where a read-modify-write crosses the bus.
vec4 sample_level(uint level, float s, float t) {
  uint C = p.channels;
  int TW = int(max(1u, p.texture_width >> level)), TH = int(max(1u, p.texture_height >> level));
  uint base = level_offset(level) * C;
  if (level > 0u) {
    // Texel centres of level l: s_l + 0.5 = (s + 0.5) W_l / W.
    s = (s + 0.5) * (float(TW) / float(p.texture_width)) - 0.5;
    t = (t + 0.5) * (float(TH) / float(p.texture_height)) - 0.5;
  }
  int i0, j0, i1, j1;
  precise float fs, ft;
  if (p.repeat != 0u) {
    s = min(max(s, -16777216.0), 16777216.0);
    t = min(max(t, -16777216.0), 16777216.0);
    float fs0 = floor(s), ft0 = floor(t);
    fs = s - fs0;
    ft = t - ft0;
    i0 = wrap(int(fs0), TW);
    j0 = wrap(int(ft0), TH);
    i1 = wrap(i0 + 1, TW);
    j1 = wrap(j0 + 1, TH);
  } else {
    s = min(max(s, 0.0), float(TW - 1));
    t = min(max(t, 0.0), float(TH - 1));
    float fs0 = floor(s), ft0 = floor(t);
    fs = s - fs0;
    ft = t - ft0;
    i0 = int(fs0);
    j0 = int(ft0);
    i1 = min(i0 + 1, TW - 1);
    j1 = min(j0 + 1, TH - 1);
  }
  uint a00 = base + (uint(j0) * uint(TW) + uint(i0)) * C, a10 = base + (uint(j0) * uint(TW) + uint(i1)) * C;
  uint a01 = base + (uint(j1) * uint(TW) + uint(i0)) * C, a11 = base + (uint(j1) * uint(TW) + uint(i1)) * C;
  vec4 out_value = vec4(0.0);
  for (uint c = 0u; c < C; ++c) {
    precise float top = (1.0 - fs) * texels[a00 + c];
    top += fs * texels[a10 + c];
    precise float bottom = (1.0 - fs) * texels[a01 + c];
    bottom += fs * texels[a11 + c];
    precise float v = (1.0 - ft) * top;
    v += ft * bottom;
    out_value[c] = v;
  }
  return out_value;
}

void main() {
  uint view = gl_WorkGroupID.z;
  uint i = gl_GlobalInvocationID.x, j = gl_GlobalInvocationID.y;
  if (i >= p.width || j >= p.height) return;
  uint bin = (view * p.tiles_y + gl_WorkGroupID.y) * p.tiles_x + gl_WorkGroupID.x;
  uint first = bin_offsets[bin], last = bin_offsets[bin + 1u];
  int px = 16 * int(i) + 8, py = 16 * int(j) + 8;
  float cx = float(i) + 0.5, cy = float(j) + 0.5;
  uint best = 0xffffffffu;
  float best_z = 0.0;
  for (uint k = first; k < last; ++k) {
    uint id = bin_items[k];
    MeshTriangle r = triangles[id];
    int e0 = edge_function(r.x1, r.y1, r.x2, r.y2, px, py);
    int e1 = edge_function(r.x2, r.y2, r.x0, r.y0, px, py);
    int e2 = edge_function(r.x0, r.y0, r.x1, r.y1, px, py);
    if (e0 < 0 || e1 < 0 || e2 < 0) continue;
    if ((e0 == 0 && !owns_edge(r.x1, r.y1, r.x2, r.y2)) || (e1 == 0 && !owns_edge(r.x2, r.y2, r.x0, r.y0)) ||
        (e2 == 0 && !owns_edge(r.x0, r.y0, r.x1, r.y1)))
      continue;
    precise float fx = cx - float(r.x0) * 0.0625;
    precise float fy = cy - float(r.y0) * 0.0625;
    float z = plane(r.inv_w[0], r.inv_w[1], r.inv_w[2], fx, fy);
    if (best == 0xffffffffu || z > best_z) { best = id; best_z = z; }
  }
  uint pix = (view * p.height + j) * p.width + i;
  if (best == 0xffffffffu) {
    coverage[pix] = 0xffffffffu;
    for (uint c = 0u; c < p.channels; ++c) pixels[pix * p.channels + c] = 0.0;
    return;
  }
  MeshTriangle r = triangles[best];
  coverage[pix] = r.index;
  precise float fx = cx - float(r.x0) * 0.0625;
  precise float fy = cy - float(r.y0) * 0.0625;
  float iw = plane(r.inv_w[0], r.inv_w[1], r.inv_w[2], fx, fy);
  precise float s = plane(r.s_w[0], r.s_w[1], r.s_w[2], fx, fy) / iw;
  precise float t = plane(r.t_w[0], r.t_w[1], r.t_w[2], fx, fy) / iw;
  float lod = 0.0;
  if (p.mip_levels > 1u) {
    // d(s, t)/d(x, y) of s = S / Iw with S, Iw affine: (S_x - s Iw_x) / Iw.
    precise float s_x = (r.s_w[1] - s * r.inv_w[1]) / iw;
    precise float s_y = (r.s_w[2] - s * r.inv_w[2]) / iw;
    precise float t_x = (r.t_w[1] - t * r.inv_w[1]) / iw;
    precise float t_y = (r.t_w[2] - t * r.inv_w[2]) / iw;
    float rho = max(sqrt(s_x * s_x + t_x * t_x), sqrt(s_y * s_y + t_y * t_y));
    lod = min(log2(max(rho, 1e-30)), float(p.mip_levels - 1u));
  }
  uint C = p.channels;
  if (!(lod > 0.0)) {
    vec4 v = sample_level(0u, s, t);
    for (uint c = 0u; c < C; ++c) pixels[pix * C + c] = v[c];
    return;
  }
  uint l0 = uint(floor(lod)), l1 = min(l0 + 1u, p.mip_levels - 1u);
  float f = lod - float(l0);
  vec4 v0 = sample_level(l0, s, t), v1 = sample_level(l1, s, t);
  for (uint c = 0u; c < C; ++c) {
    // The CPU oracle's order: (1 - f) v0, then + f v1, each rounded (no fused multiply-add).
    precise float w = 1.0 - f;
    precise float r = w == 1.0 ? v0[c] : w * v0[c];
    r += f * v1[c];
    pixels[pix * C + c] = r;
  }
}
