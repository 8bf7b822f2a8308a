// Packing charts into a texture atlas, and choosing the atlas size from a pixel budget.
//
// Only translations and quarter turns are used: any other rotation would undo the
// orientation that the mesh stage optimized. The packer places each chart's rasterized
// footprint, not its bounding box, so L-shaped and diagonal charts interlock. It is a
// bottom-left fill over a bitmap of the cells already taken (dilated by the gutter): each
// chart, biggest first, goes to the first free position in reading order of the best of its
// four orientations, so holes under overhangs and between charts are refilled by smaller
// charts. A few orderings and orientation rules are tried in turn until one fits (no single
// rule packs every asset best). A position test is a few 64-bit word operations per row of
// the footprint, and a failed test jumps the scan past the cells that blocked it.
//
// Coordinates: atlas texel space, x to the right, y down (image rows, as glTF v), texel
// (i, j) covers [i, i+1) x [j, j+1). A chart's footprint is every texel whose square
// overlaps one of its triangles with positive area (conservative rasterization). Between
// the footprints of any two charts there are at least `gutter` empty texels (Chebyshev
// distance, i.e. also diagonally), and `gutter` empty texels between footprints and the
// image edge. With `block` = b > 1 (4 for BCn), packing happens on b x b cells: footprints
// are sets of whole cells, chart origins sit on multiples of b, chart extents are whole
// cells, the gutter is rounded up to whole cells, and no b x b block holds texels of two
// charts. Everything is deterministic and single-threaded (a serial scan with exact
// pruning; candidates are ordered by (cost, y, x, rotation)).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace uvpress::atlas {

// One chart to pack: a 2-D triangle mesh in texel units of the source density (scale 1
// means one unit = one atlas texel), at any position.
struct ChartShape {
  std::vector<double> points;       // x y per vertex
  std::vector<uint32_t> triangles;  // 3 indices per triangle
  // Place with a whole-texel translation: the footprint's origin is the scaled chart's
  // minimum corner rounded down to a texel, so texel (i, j) of the scaled chart's own grid
  // lands on a texel of the atlas (the chart's texels can then be copied, not resampled).
  bool snap = false;
  // With snap: the translation is a multiple of `align` texels too (a power of two that the
  // block divides; otherwise ignored), so that each 2^k x 2^k block of the copied texels (k
  // up to log2 align) lands on one texel's block of the atlas's mip level k. A renderer's
  // mip chain then averages the same texels as the source's own chain at those levels,
  // instead of the blocks of another phase: Duck's own charts copied at scale 1 into a
  // 512 x 512 image score q 0.00057 over eval's trilinear views at any whole-texel offset,
  // 0.00019 at multiples of 16 (bilinear, level 0 only: 5e-9 either way).
  uint32_t align = 1;
  // Packed at scale 1 whatever the packing's scale (ChartPlacement::scale): a chart whose
  // texels are copied from the source at its own density. The packing's scale then applies
  // to the other charts alone, which take all the slack that rounding and alignment leave:
  // with one uniform scale, Fox's two copied charts aligned to its 16-texel mip phase fit only
  // at scale 0.983, and were then copied from the source resized to 0.983, not from itself.
  bool pinned = false;
};

struct PackOptions {
  uint32_t gutter = 4;  // empty texels between charts
  // Empty texels between footprints and the image's left and right edges (edge_x) and its
  // top and bottom edges (edge_y). Only a sampler that repeats reads across an edge (its
  // bilinear taps and coarse mip texels wrap to the far side), and there half the gutter on
  // each side keeps the full gutter across the wrap; one that clamps or mirrors reads the
  // chart's own edge texels (edge_gutter below).
  // kEdgeAsGutter: the gutter itself (a sampler of unknown wrap mode).
  static constexpr uint32_t kEdgeAsGutter = UINT32_MAX;
  uint32_t edge_x = kEdgeAsGutter, edge_y = kEdgeAsGutter;
  uint32_t block = 1;   // 1, or 4 for BCn block alignment
  bool rotate = true;   // allow quarter turns
};

// The alignment (ChartShape::align, BudgetOptions::side_multiple) that keeps a copied
// chart's mip blocks whole at every level the gutter keeps apart: the largest power of two
// <= gutter, where `block` divides it (else 1: a 5- or 6-texel block grid has no
// power-of-two phase in common with the mips).
uint32_t mip_phase_align(uint32_t gutter, uint32_t block);

// The empty texels a chart needs between itself and an image edge, for `gutter` between
// charts and a sampler axis that repeats (GL REPEAT) or not (CLAMP_TO_EDGE, MIRRORED_REPEAT).
inline uint32_t edge_gutter(uint32_t gutter, bool repeats) { return repeats ? (gutter + 1) / 2 : 0; }

// Where one chart goes: atlas = R_k (scale * p) + t (the placement's scale), with R_k = R_1^k and
// R_1 (x, y) = (-y, x) (in the y-down image a clockwise quarter turn).
struct ChartPlacement {
  uint32_t rotation = 0;  // k in {0, 1, 2, 3}
  double scale = 1;       // the packing's scale, or 1 for a pinned chart (ChartShape::pinned)
  double tx = 0, ty = 0;
  // Texel cell of the footprint's bounding box corner and its size in texels (multiples of
  // the block size).
  uint32_t x = 0, y = 0, width = 0, height = 0;
};

struct Packing {
  bool ok = false;
  uint32_t width = 0, height = 0;  // atlas size in texels
  double scale = 1;                // uniform scale applied to every chart not pinned
  std::vector<ChartPlacement> placements;  // one per chart, in input order
  double chart_area = 0;     // sum of |triangle areas| after scaling, texels^2 (eq. 20: overlaps count twice)
  double covered = 0;        // atlas texels whose centre a chart covers (overlapping charts count once)
  double efficiency = 0;     // covered / (width * height): the share of the image under charts
  double gutter_texels = 0;  // texels kept empty for gutters (around footprints and along the edges)
  // Texels of the charts' footprints (every texel a triangle overlaps: covered texels and the
  // rims that bilinear taps read). Image = footprints + gutters + what the packer left free.
  double footprint_texels = 0;

  // Chart point (input units) -> atlas texel coordinates.
  std::array<double, 2> map(size_t chart, double x, double y) const;
  // ... -> atlas UV in [0,1] (glTF convention, v down).
  std::array<double, 2> map_uv(size_t chart, double x, double y) const;
};

// (a) Packs the charts at `scale` into width x height. ok = false when they don't fit.
Packing pack_charts(const std::vector<ChartShape>& charts, uint32_t width, uint32_t height, double scale = 1.0,
                    const PackOptions& options = {});

// (b) The largest scale s <= s_max at which pack_charts succeeds (pinned charts at 1
// throughout), by bisection to relative tolerance `tolerance` (a scale s (1 + tolerance)
// failed, or s == s_max). The heuristic packer is not strictly monotone in s, so "largest"
// is local: s fits, s (1 + tolerance) does not. ok = false when nothing fits even at scale
// 1e-6 (too many charts for the gutters, or pinned charts that alone overfill the image).
Packing pack_max_scale(const std::vector<ChartShape>& charts, uint32_t width, uint32_t height,
                       const PackOptions& options = {}, double s_max = 1.0, double tolerance = 1e-3);

// (c) Atlas size from a budget.
enum class CostMeasure {
  ChartTexels,  // eq. 20-21: c = r^2 sum|triangle uv area|, i.e. texels under the charts
  ImageTexels,  // texels of the whole image (memory / file size)
};

struct BudgetOptions {
  double cost = 0.5;    // target relative cost c_r (used when size == 0)
  CostMeasure measure = CostMeasure::ChartTexels;
  uint32_t size = 0;    // --size N: the atlas's longer side is N (the budget is ignored)
  bool pot = false;     // power-of-two sides
  // true: the source's aspect ratio. false: also 2:1 and 1:2 of it (then 4:1 or 1:4 where
  // that direction won), and for ImageTexels without pot many shapes between them (see
  // choose_atlas), keeping another shape only when it gives 1 % more scale or 1 % fewer
  // image texels: a long chart then gets a long atlas, and a set of charts the shape that
  // the packer fills best.
  bool keep_aspect = true;
  double s_max = 1.0;   // never above the source texel density
  // Sides multiples of this too (where pack.block divides it, else of the block alone; with
  // pot they are anyway): a
  // power of two 2^K makes mip levels 1..K of the image exact 2 x 2 boxes of the level
  // above. An odd side halves to a fraction, and a renderer's chain (eval's too) then
  // filters by 2.0x and drifts against level 0: Duck's own charts copied at scale 1 score
  // q 0.00057 in a 512 x 512 image and 0.00070 in 514 x 432, the Lanczos resize of Duck to
  // 256 x 256 0.00050 and to 0.249 of its texels 0.00081 (eval's trilinear views).
  uint32_t side_multiple = 1;
  PackOptions pack;
};

struct AtlasChoice {
  Packing packing;        // size, scale, placements, efficiency
  double cost_ratio = 0;  // achieved c_r = the scaled chart area / old_used_texels (eq. 21; pinned charts at 1)
  double texel_ratio = 0; // width * height / (old_width * old_height)
};

// Picks width x height and the scale for the charts (given at the source texel density:
// scale 1 = one unit per source texel). old_used_texels is c of the input layout (eq. 20:
// the source texels under the input's charts); only ChartTexels needs it, but cost_ratio
// is reported from it when > 0.
//  - size > 0: longer side = size (rounded to a power of two with pot), shorter side by the
//    source aspect; the scale is the largest that fits (<= s_max).
//  - ChartTexels: scale = min(s_max, sqrt(cost * old_used / chart area)) (pinned charts: their
//    area at scale 1 spent first, the scale from what is left of the budget; none left: ok =
//    false), then the smallest atlas of the source aspect that holds the charts at that
//    scale; with pot, the power-of-two size nearest (in log area) to that atlas, and the
//    scale is then re-fitted to it (so c_r is only approximate with pot).
//  - ImageTexels: width * height <= cost * old_width * old_height (the shape's largest within
//    it: where both sides rounded would exceed it, the shorter side gives way, or the longer
//    one by a block if that keeps more), then the largest scale;
//    when that scale reaches s_max the atlas shrinks to the smallest that still fits.
// Sides are multiples of the block size (and of side_multiple). ok = false when nothing fits. With keep_aspect
// false: the source's aspect, 2:1 and 1:2 of it (then 4:1 or 1:4), and for ImageTexels
// without pot also steps of 2^(1/4) between them, the largest chart's own shape and steps
// of 2^(1/8), 2^(1/16) about the best; a shape is searched in full only where one
// placement says it may hold the charts at 1 % more scale. Shapes are searched
// independently (in parallel) and compared in a fixed order, so the choice does not depend
// on the thread count.
AtlasChoice choose_atlas(const std::vector<ChartShape>& charts, uint32_t old_width, uint32_t old_height,
                         double old_used_texels, const BudgetOptions& options = {});

// Whether triangle (a, b, c) overlaps the box [x0,x1] x [y0,y1] by more than eps (touching
// along an edge or at a corner does not count). Exact separating-axis test; eps is a
// distance in the same units.
bool triangle_overlaps_box(const double a[2], const double b[2], const double c[2], double x0, double y0, double x1,
                           double y1, double eps = 1e-9);

}  // namespace uvpress::atlas
