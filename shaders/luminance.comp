#version 450
// GMSD step 1 (reference/gmsd.md): Y = 0.299 R + 0.587 G + 0.114 B on the stored
// (sRGB-encoded) 8-bit values scaled to [0,1], no rounding. Input: RGBA8 packed
// little-endian in one uint per pixel. One invocation per pixel, one z-slice per image.
#extension GL_GOOGLE_include_directive : require
#include "layout.h"

layout(local_size_x_id = 0, local_size_y_id = 1, local_size_z = 1) in;
layout(std430, binding = 0) readonly buffer Rgba { uint rgba[]; };
layout(std430, binding = 1) writeonly buffer Lum { float lum[]; };
layout(push_constant) uniform Push { ImageBatchPush p; };

void main() {
  uint x = gl_GlobalInvocationID.x, y = gl_GlobalInvocationID.y;
  if (x >= p.width || y >= p.height) return;
  uint i = (p.first + gl_WorkGroupID.z) * p.width * p.height + y * p.width + x;
  uint c = rgba[i];
  float r = float(c & 0xffu), g = float((c >> 8) & 0xffu), b = float((c >> 16) & 0xffu);
  // precise: the CPU oracle evaluates the same expression unfused, in this order.
  precise float y8 = 0.299 * r + 0.587 * g + 0.114 * b;
  lum[i] = y8 * (1.0 / 255.0);
}
