// Fixed-point rasterization helpers shared by the view kernels; the C++ twin is
// engine/cpu/view_raster.cpp.
#ifndef UVPRESS_VIEW_RASTER_GLSL
#define UVPRESS_VIEW_RASTER_GLSL

// 4 sub-pixel bits; floor(v * 16 + 0.5) rounds the same way as the CPU backend.
int snap16(float v) { return int(floor(v * 16.0 + 0.5)); }

int edge_function(ivec2 a, ivec2 b, ivec2 p) { return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x); }

// Top-left rule for a positively oriented triangle.
bool owns_edge(ivec2 a, ivec2 b) {
  int dx = b.x - a.x, dy = b.y - a.y;
  return dy > 0 || (dy == 0 && dx < 0);
}

float plane_at(float c0, float c1, float c2, float x, float y) {
  precise float v = c0 + c1 * x;
  v += c2 * y;
  return v;
}

#endif
