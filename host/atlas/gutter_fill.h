// Filling the gutters for the mip chain.
//
// A viewer builds the mip chain itself (glGenerateMipmap: 2x2 box averages, colour in
// linear light), so the written image controls level 0 only; yet far away, and at grazing
// angles even near, what is sampled is a coarse level, whose texels average 2^k x 2^k
// blocks of level 0. Every gutter texel reaches the screen through each level whose block
// holds it and a chart texel, so the fill decides what colour a chart's edge has at a
// distance. The fill:
//
//  1. Ring: empty texels whose nearest chart texel (exact Euclidean distance transform,
//     ties to the first in scan order) is at most `ring` texels away in x and in y take
//     that texel's value. Bilinear taps just outside a chart's footprint at level 0 read its
//     edge colour, as with a nearest fill. After a bake with a surround (the source's own
//     surroundings baked into half the gutter, RebakeOptions::surround) the ring is as wide
//     as the surround (atlas::fill_ring): between charts a gutter apart the surrounds meet
//     and nothing is left to fill, but free space next to a chart then continues the
//     surround's outer texels, as the input continues its background, where the pull-push
//     would put the mean of a block of chart and surround that coarse levels blend into the
//     chart's edge. Fox at half its texels, from afar (eval's views with the fox filling
//     256 pixels): q 0.00352 with a one-texel ring, 0.00259 with the surround's 8, the
//     resize 0.00117; up close, Duck, CesiumMilkTruck and MultiUVTest within 0.3 %.
//  2. Mip-consistent pull-push: the known texels (charts and ring) are averaged up a
//     pyramid of 2x2 blocks aligned to the image's origin (a block's value: the mean of its
//     non-empty children's values, colour channels in linear light when `srgb`), each block
//     labelled with the chart it holds — an 8-connected component of the known texels — or
//     as holding several. An empty texel takes the value of the smallest non-empty block
//     around it when that block holds one chart: then every block, at every level, that
//     holds texels of one chart and no other averages to that chart's own (binary-weighted)
//     mean — the chart's colour extended through the whole mip chain, neither background
//     nor a neighbour's. Where the smallest non-empty block holds two charts (the gutter
//     between them narrower than the block), the texel takes its nearest chart texel's
//     value instead: each chart's colour reaches the midline between them.
//
// So a chart's own colour is clean at level k wherever no 2^k-aligned block of 2^k texels
// holds texels of another chart: guaranteed at every level k with 2^k <= the gutter
// between footprints (atlas/pack.h), and the gutter sets how coarse a level stays clean
// (mip_safe_gutter below).
#pragma once

#include "core/image.h"

#include <cstdint>
#include <vector>

namespace uvpress::atlas {

// Every texel with covered == 0 (width * height bytes, row 0 on top) is filled as above;
// covered texels are left as they are. `srgb`: the image's colour channels (all but an
// alpha channel) are sRGB-encoded and averaged in linear light (the filled values are
// re-encoded); otherwise every channel is averaged as stored. Nothing happens when no
// texel or every texel is covered. Deterministic.
void fill_gutter(Image& image, const std::vector<uint8_t>& covered, bool srgb = false, uint32_t ring = 1);

// Gutter texels that no mip level reads near a chart, made flat without changing any level
// that does. A renderer samples a chart at level k bilinearly from a point inside one of its
// triangles, so it reads level-0 texels less than 1.5 x 2^k texels (Chebyshev distance) from
// the chart's footprint; a texel d >= 2^j texels away is therefore read near a chart by levels
// j and coarser alone, and those average it over the aligned 2^j x 2^j block that holds it
// (a box-filtered chain, glGenerateMipmap's, from sides that are multiples of 2^j). Such a
// texel (2^j the largest power of two <= d, at most `max_block` and at most the largest power
// of two that divides both sides) takes the mean of the texels of its block that do likewise:
// every block's sum at level j and coarser stays what it was, so every level that reads the
// texel shows the same colour there, and the finer levels, which would see the change, never
// look there. What the surround and the fill bring to the coarse levels stays; the detail they
// carry at level 0, which nothing on screen samples, goes, and with it bytes (README, Bytes).
// An odd side gets nothing: its chain's blocks drift against level 0's (a 717-texel side halves
// to 358 texels of 2.003), and a flattened block would change what they average.
// The reach assumes isotropic filtering (three.js's default, eval's views): anisotropic taps
// spread along a footprint's long axis and can read flattened texels at level 0 near a
// chart seen edge-on. `max_block` at most 128.
// `footprint` (width * height, 1 = a triangle overlaps the texel: RebakeStats::footprint);
// `srgb` as fill_gutter (means in linear light, alpha as stored); `wrap_x`, `wrap_y`: the
// sampler repeats across that edge, so distances wrap around (clamping and mirroring read
// no texel nearer a chart than the edge texel itself). Exact but for 8-bit rounding of the
// means. Deterministic; nothing happens without a footprint texel.
void coarsen_gutter(Image& image, const std::vector<uint8_t>& footprint, bool srgb, bool wrap_x = true,
                    bool wrap_y = true, uint32_t max_block = 64);

// The gutter (texels between charts, atlas/pack.h) that keeps every mip level clean down to
// the first whose side is at most `coarsest_side` texels, for an image of `image_texels`
// (W x H; the side taken as sqrt(W H)): with the fill above a level k is clean when the
// gutter is at least 2^k, so this is 2^ceil(log2(side / coarsest_side)), at least
// `minimum` and at most `maximum`. A fixed screen size sees a level that many times finer
// as the image grows, so the gutter grows with the image's side (a 362^2 image: 8 texels,
// clean down to its 45^2 level; 1024^2 and up: 16). The defaults are the measured ones
// (README, "Gutters"): Duck at half its texels (362^2) seen from a third of a 256-pixel
// view in three.js (tests/client) bleeds at a 4- or 6-texel gutter and is clean at 8; the
// cap of 16 (twice the artists' 8 at 2048^2) because wider ones cost the eval score more
// than the far views gain (CesiumMilkTruck at half its texels: packing efficiency 0.71 at
// 4, 0.65 at 16, 0.56 at 32, with the same three.js figures at 16 and 32).
uint32_t mip_safe_gutter(double image_texels, uint32_t coarsest_side = 64, uint32_t minimum = 4, uint32_t maximum = 16);

}  // namespace uvpress::atlas
