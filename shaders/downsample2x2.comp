#version 450
// GMSD step 2 (reference/gmsd.md): D(i,j) = 1/4 [Y(2i,2j) + Y(2i+1,2j) + Y(2i,2j+1) +
// Y(2i+1,2j+1)], output ceil(H/2) x ceil(W/2), pixels outside Y are 0. One invocation per
// output pixel; the sum is formed in a fixed order so every backend rounds alike.
#extension GL_GOOGLE_include_directive : require
#include "layout.h"

layout(local_size_x_id = 0, local_size_y_id = 1, local_size_z = 1) in;
layout(std430, binding = 0) readonly buffer Src { float src[]; };
layout(std430, binding = 1) writeonly buffer Dst { float dst[]; };
layout(push_constant) uniform Push { ImageBatchPush p; };

float at(uint base, uint x, uint y) {
  return (x < p.width && y < p.height) ? src[base + y * p.width + x] : 0.0;
}

void main() {
  uint w2 = (p.width + 1u) / 2u, h2 = (p.height + 1u) / 2u;
  uint x = gl_GlobalInvocationID.x, y = gl_GlobalInvocationID.y;
  if (x >= w2 || y >= h2) return;
  uint image = p.first + gl_WorkGroupID.z;
  uint base = image * p.width * p.height;
  precise float s = ((at(base, 2u * x, 2u * y) + at(base, 2u * x + 1u, 2u * y)) +
                     at(base, 2u * x, 2u * y + 1u)) + at(base, 2u * x + 1u, 2u * y + 1u);
  dst[image * w2 * h2 + y * w2 + x] = 0.25 * s;
}
