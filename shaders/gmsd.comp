#version 450
// GMSD of image pairs (reference/gmsd.md): one workgroup per pair.
#extension GL_GOOGLE_include_directive : require
#include "layout.h"

layout(local_size_x_id = 0) in;  // the engine's workgroup size (a multiple of 8)
layout(std430, binding = 0) readonly buffer A { float image_a[]; };
layout(std430, binding = 1) readonly buffer B { float image_b[]; };
layout(std430, binding = 2) writeonly buffer Out { float result[]; };
layout(push_constant) uniform Push { GmsdPush p; };

uint g_base;

float gmsd_a(int x, int y) {
  return (x < int(p.width) && y < int(p.height)) ? image_a[g_base + uint(y) * p.width + uint(x)] : 0.0;
}
float gmsd_b(int x, int y) {
  return (x < int(p.width) && y < int(p.height)) ? image_b[g_base + uint(y) * p.width + uint(x)] : 0.0;
}

#include "gmsd.glsl"

void main() {
  uint pair = p.first + gl_WorkGroupID.x;
  g_base = pair * p.width * p.height;
  float g = gmsd_run(p.width, p.height);
  if (gl_LocalInvocationIndex == 0u) result[pair] = g;
}
