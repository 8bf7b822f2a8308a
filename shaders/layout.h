// Structs shared verbatim by GLSL and C++ (std430 / push-constant rules: only 32-bit
// scalars, members in declaration order, no implicit padding), so the two sides of a
// kernel's interface cannot drift. Include from GLSL with GL_GOOGLE_include_directive.
#ifndef UVPRESS_SHADER_LAYOUT_H
#define UVPRESS_SHADER_LAYOUT_H

#ifdef __cplusplus
#include <cstdint>
namespace uvpress::shader {
typedef uint32_t uint;
#endif

// One dispatch over `count` equal-sized images of a batch, starting at image `first`
// (relative to the bound buffers). Grid: (ceil(width/lx), ceil(height/ly), count).
struct ImageBatchPush {
  uint width;   // of the input image, pixels
  uint height;
  uint first;   // first image of this dispatch within the bound buffers
  uint count;   // images in this dispatch
};

// ---- Per-triangle views (perceptual loss, seed paper 001 section 4.1.1, Appendix A) ----
//
// A view is an S x S orthographic render of one triangle and its one-ring (or, for a
// triangle too large in texels to resolve in one view, of one square patch of it: see
// host/perceptual/triangle_view.h). The host gives every ring triangle in view space:
// screen vertices in pixels (x right, y down; pixel (i, j) has its centre at
// (i + 0.5, j + 0.5)), and three affine planes over the screen,
// value(x, y) = c0 + c1 x + c2 y, for depth (larger is nearer the camera) and for the
// source texel coordinates s, t (texel centres at integers: s = u W - 0.5, t = v H - 0.5).
//
// Ring triangles are grouped by chart: a neighbour across a UV seam lives elsewhere in the
// texture, and in the re-parameterized atlas it will have its own texels, so the candidate
// gets one least-squares region per group, each with J applied about the group's anchor (an
// integer-valued texel position: J = I then keeps that group's texel lattice exactly).
struct ViewTriangle {
  float xy[6];     // x0 y0 x1 y1 x2 y2, pixels; |x|, |y| <= kViewGuardBand
  float depth[3];  // plane coefficients
  float s[3];
  float t[3];
  float anchor_s;  // integer-valued texel coordinates J acts about, equal within a group
  float anchor_t;
  uint group;      // 0 for the view's own chart, < ViewDesc::group_count
  uint pad0, pad1;
};

struct ViewDesc {
  uint first_triangle;  // into the ViewTriangle array; the view's own triangle comes first
  uint triangle_count;  // 1 + one-ring, at most kViewMaxTriangles
  uint group_count;     // charts among the ring triangles, 1..kViewMaxGroups
  uint pad;
};

// One candidate Jacobian (texel space, row-major: s' = j0 s + j1 t, t' = j2 s + j3 t) for
// one view. The candidate texture is a tile of texels on the lattice of J-mapped source
// texel coordinates (one region per group, shelf-packed into the tile), fitted by least
// squares to the view's reference render (eq. 11).
struct ViewCandidate {
  float j[4];
  uint view;
  uint pad0, pad1, pad2;
};

// Dispatch over a page of views: `count` items starting at `first`.
struct ViewPush {
  uint size;              // S, pixels per side
  uint first;             // first view (prepare) or candidate (score) of this dispatch
  uint count;
  uint texture_width;     // prepare only: the source luminance texture
  uint texture_height;
  uint view_base;         // index of the first view held by the bound page
  uint store_images;      // score only: 1 = write the candidate render for read-back
  uint pad;
};

// GMSD of `count` image pairs of width x height each.
struct GmsdPush {
  uint width;
  uint height;
  uint first;
  uint count;
};

// ---- Whole-mesh renders (eval: engine::MeshRenderDesc, render_mesh.comp) ----
//
// One set-up triangle of one view, made on the host (engine/mesh_setup.cpp) for both
// backends: vertices snapped to 1/16 pixel and positively oriented, and three affine planes
// over the screen relative to vertex 0, value(x, y) = c0 + c1 (x - x0/16) + c2 (y - y0/16),
// for 1/w (larger is nearer) and for s/w, t/w (s, t texel coordinates, s = u W - 0.5).
struct MeshTriangle {
  int x0, y0, x1, y1, x2, y2;
  float inv_w[3];
  float s_w[3];
  float t_w[3];
  uint index;  // triangle index in the mesh: coverage value and depth tie-break
};

// Views are binned in kMeshTile x kMeshTile pixel tiles; each tile lists the set-up
// triangles whose pixel box meets it, in increasing triangle index.
struct MeshPush {
  uint width;   // pixels
  uint height;
  uint tiles_x;
  uint tiles_y;
  uint texture_width;
  uint texture_height;
  uint channels;  // 1..4 floats a texel and a pixel
  uint repeat;    // 1: REPEAT wrapping, 0: clamp-to-edge
  uint mip_levels;  // levels in the texture buffer, level after level (1: bilinear from level 0)
  uint pad0;
  uint pad1;
  uint pad2;
};

// ---- Re-bake sampling (engine::RebakeTexelsDesc, rebake.comp) ----
//
// One entry of a tile's triangle list, in the tile's own frame (texel units, origin at the
// tile's top-left corner). Every quantity x that the kernel combines with a texel's integer
// offset (lx, ly) in the tile is split as x = xh + xl, xh on a grid of 2^-12: xh * lx is
// then exact in fp32, so distances and source positions at a texel keep ~1e-7 texel
// precision whatever the sizes of the triangle and the images.
// Edge e runs from vertex e to vertex e+1: unit tangent u (u[2e], u[2e+1]), inward unit
// normal n = sign (-u_y, u_x); p is inside when n.p >= c for all three edges; s0 = u.a and
// s1 = u.b are its ends along u. The source position of tile point p, in source texels, is
// (oi + of) + J p, oi integer, J row-major.
struct RebakeEntry {
  float uh[6], ul[6];
  float ch[3], cl[3];
  float s0h[3], s0l[3];
  float s1h[3], s1l[3];
  float sign;
  float jh[4], jl[4];
  int oi[2];
  float of[2];
  uint ns;            // samples per axis: x | y << 16
};

// One dispatch over tile rows [tile_row0, tile_row0 + groups_y) of the new image. The bound
// buffers hold tile rows from chunk_row0 on (owner, output) and list entries from
// entry_base on.
struct RebakePush {
  uint width;          // new image, texels
  uint height;
  uint tiles_x;
  uint tile_row0;
  uint chunk_row0;
  uint entry_base;
  uint source_width;
  uint source_height;
  uint channels;       // 1..4
  uint wrap_s;         // 0 repeat, 1 clamp-to-edge, 2 mirrored repeat
  uint wrap_t;
  uint premultiplied;  // 1: un-premultiply by the last channel
  uint source_split;   // source texels per source buffer (4 buffers)
  uint pad0, pad1, pad2;
};

#ifdef __cplusplus
constexpr uint kViewMaxSize = 64;         // S <= 64: GMSD works on a 32 x 32 shared tile
constexpr uint kViewMaxTriangles = 64;    // 1 + one-ring
constexpr uint kViewGuardBand = 511;      // |screen coordinate| bound: 4 sub-pixel bits keep edge functions in int32
// Candidate tile, texels per side: a view resolves its texels (at most one texel a pixel,
// host/perceptual/triangle_view.h), so J (|J| <= 1) maps its S x S pixels into at most
// S sqrt(2) texels a side, plus the bilinear footprint: 64 sqrt(2) + 3 < 96 for one chart,
// and 128 leaves room for a seam neighbour's region beside it. A tile that would still be
// larger (anisotropic UVs, regions that do not fit together) falls back to a coarser
// power-of-two lattice, which the engine reports (score_views' `lattice`).
constexpr uint kTileMax = 128;
constexpr uint kViewMaxGroups = 8;        // charts in one view's ring
constexpr uint kViewMaxTexelsPerPixel = 64;  // |d(s, t)/d(x, y)| bound of a view triangle's planes
// view_score.comp's scratch slot per candidate, 32-bit words: 4 per pixel (u, v, candidate,
// group), 15 per tile texel (stencil 9, rhs, x, r, Ap, diagonal, p) plus p's zero padding.
constexpr uint kViewScoreSlotWords = 4 * kViewMaxSize * kViewMaxSize + 14 * kTileMax * kTileMax + (kTileMax + 2) * (kTileMax + 2);
constexpr uint kNoTriangle = 255;         // coverage value of an empty pixel
static_assert(sizeof(ViewTriangle) == 80, "std430 layout");
static_assert(sizeof(ViewDesc) == 16, "std430 layout");
static_assert(sizeof(ViewCandidate) == 32, "std430 layout");
static_assert(sizeof(ViewPush) == 32, "push constant layout");
static_assert(sizeof(ImageBatchPush) == 16, "push constant layout");
constexpr uint kMeshTile = 16;            // render_mesh.comp: one 16 x 16 workgroup a tile
static_assert(sizeof(MeshTriangle) == 64, "std430 layout");
static_assert(sizeof(MeshPush) == 48, "push constant layout");
constexpr uint kRebakeTile = 16;          // re-bake tiles (host binning, rebake.comp workgroups)
static_assert(sizeof(RebakeEntry) == 176, "std430 layout");
static_assert(sizeof(RebakePush) == 64, "push constant layout");
}  // namespace uvpress::shader
#else
#define kViewMaxSize 64u
#define kViewMaxTriangles 64u
#define kViewGuardBand 511u
#define kTileMax 128u
#define kViewMaxGroups 8u
#define kViewMaxTexelsPerPixel 64u
#define kNoTriangle 255u
#define kMeshTile 16u
#define kRebakeTile 16u
#endif

#endif
