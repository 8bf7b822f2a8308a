// The per-triangle view kernels of the CPU backend, written to mirror the GLSL ones
// (view_prepare.comp, view_score.comp) operation for operation: they are the oracle the
// Vulkan path is tested against. Conventions in shaders/layout.h.
#pragma once

#include "layout.h"

#include <cstdint>
#include <vector>

namespace uvpress::engine::cpu {

using shader::ViewCandidate;
using shader::ViewDesc;
using shader::ViewTriangle;

// Coverage and reference render of one view: per pixel the nearest ring triangle (integer
// edge functions at 1/16 pixel, top-left rule, larger depth wins, ties to the earlier
// triangle) and the bilinear, clamp-to-edge sample of the source luminance there.
void rasterize_view(const ViewDesc& view, const ViewTriangle* triangles, uint32_t size, const float* texture,
                    uint32_t texture_width, uint32_t texture_height, uint8_t* coverage, float* reference);

// Where each covered pixel lands in a candidate's texture tile: tile coordinates (a, b)
// with texel (i, j) at integer (i, j); the tile is `width` x `height` <= kTileMax squared.
// Pixel q of ring triangle k maps to J ((s, t)_q - anchor_k) in its group's region; the
// regions (one per group, each its J-mapped bounding box plus the bilinear footprint) are
// laid out on shelves of kTileMax texels with one texel between them.
struct TileMap {
  uint32_t width = 0, height = 0;
  float lattice = 1;           // tile texel spacing in J-mapped source texels: 1, or a power of
                               // two when the regions would not fit in kTileMax (not faithful)
  std::vector<uint32_t> pixel;  // covered pixel indices, in raster order
  std::vector<float> a, b;     // their tile coordinates
};
TileMap map_to_tile(const ViewDesc& view, const ViewTriangle* triangles, uint32_t size, const uint8_t* coverage,
                    const float j[4]);

// The part of the tile map that does not depend on J, made once per view (prepare_views)
// rather than once per candidate: the covered pixels, each one's (s, t) - anchor_k of its
// ring triangle k (texels) and its group.
struct ViewPixels {
  uint32_t groups = 1;
  std::vector<uint32_t> pixel;  // covered pixel indices, in raster order
  std::vector<float> ds, dt;
  std::vector<uint8_t> group;
};
ViewPixels view_pixels(const ViewDesc& view, const ViewTriangle* triangles, uint32_t size, const uint8_t* coverage);
// map_to_tile of the view `pixels` was made from: the same map, bit for bit.
TileMap map_to_tile(const ViewPixels& pixels, const float j[4]);

// Fixed-point scale of the normal-equation sums: integer sums are exact and order-free,
// so a GPU accumulating them with atomics gets the CPU's numbers bit for bit.
constexpr float kFixedPoint = 65536.0f;
// Smoothness weight, relative to covered pixels per texel: a small membrane term
// mu sum_edges (T_i - T_j)^2 over the tile's 4-neighbour edges makes A^T A definite and
// fills texels no pixel sees from their neighbours (a pull towards a constant would bias
// the weakly seen texels at the coverage border instead).
constexpr float kSmoothness = 1e-4f;
// Preconditioned CG stops when its render is within kBakeRenderTolerance (RMS over the
// covered pixels, luminance in [0, 1]) of the exact least-squares render, or after
// kBakeMaxIterations. The test is CG's own error estimate: ||x* - x_k||_A^2 is the sum of
// alpha_i (r_i . z_i) over i >= k (Hestenes & Stiefel 1952, eq. 6:2; Strakos & Tichy 2002),
// taken over the last kBakeDelay iterations, and ||e||_A^2 >= sum_q (W e)_q^2, the render's
// squared error. A relative residual cannot tell the modes the render shows from those it
// does not: near J = I the pixels barely see the lattice's finest modes, the membrane alone
// holds them, and CG spent up to 200 iterations on them at ||r|| <= 1e-5 ||b||.
// The tolerance is absolute because flat triangles' losses are tiny (Fox's median shrink
// cost is 1e-6) and the allocation compares them. Measured on Fox's triangle stage against
// a solve to ||r|| <= 1e-7 ||b||, the candidates' GMSD differ by at most 2.6e-6 (mean
// 6.3e-8) after 23 iterations on average; the relative residual of 1e-5 took 41 and erred by
// up to 6.5e-6 (mean 1.6e-7). A tolerance of 3e-5 took 15 but moved losses of 1e-6 by up to
// 9x and made Fox's equal-slope layouts 6-20 % worse on screen. Four terms of the series are
// a lower bound of the error; against a direct solve of the same fixed-point system the
// render's RMS error stayed under 0.75x the tolerance where CG converges slowest
// (test_views.cpp).
constexpr float kBakeRenderTolerance = 5e-6f;
constexpr uint32_t kBakeDelay = 4;
constexpr uint32_t kBakeMaxIterations = 200;

// The least-squares bake (eq. 11) with the membrane term:
//   min_T sum_q (sum_k w_qk T_k - ref_q)^2 + mu sum_(i,j) (T_i - T_j)^2,
// solved for T - m (m the mean reference luminance, the starting guess). Returns the tile
// texels T (width * height), or with `mean` the solution T - m and m there.
std::vector<float> bake_tile(const TileMap& map, const float* reference, uint32_t* iterations = nullptr,
                             float* mean = nullptr);

// Bilinear render of `tile` at the mapped pixels, plus `offset`; empty pixels stay 0.
void render_tile(const TileMap& map, const std::vector<float>& tile, uint32_t size, float* candidate,
                 float offset = 0);

// Everything for one candidate: map, bake, render, GMSD against the reference; the tile's
// lattice spacing in `lattice` when given.
float score_view(const ViewPixels& pixels, uint32_t size, const float* reference, const float j[4], float* candidate,
                 float* lattice = nullptr);

}  // namespace uvpress::engine::cpu
