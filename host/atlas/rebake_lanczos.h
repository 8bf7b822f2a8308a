// Lanczos re-bake: each new texel the Lanczos-3 filter of the source, warped by its
// triangle's affine map, so that a reshaped chart is resampled as sharply as a plain resize.
//
// rebake() (area filter: the mean of bilinear samples over the texel's footprint) blurs
// more than the Lanczos-3 resize users compare against: on the demo at half the texels, the
// stretch-only-outline layout scores q 0.030 over eval's 20 views area-baked and 0.022
// baked by this filter (the plain resize: 0.025). This bake evaluates, per covered texel, the
// separable Lanczos-3 kernel in the new image's texel axes (where the layout shrinks the
// source, as a resize does: support 3 new texels) or in the source's (where it magnifies:
// Lanczos interpolation), through the owner triangle's map d old / d new = J = U S V^T:
// a source texel at offset d from the texel centre's preimage has kernel coordinates
// V min(S^-1, 1) U^T d. For a uniform scale that is the Lanczos-3 resize itself.
//
// Values are filtered as stored (the resize does the same: "lanczos3-srgb"), normalized by
// the kernel's sum and clamped to [0, 1] (Lanczos rings); the source is read through the
// sampler's wrap modes. A kernel reads the texels of its own chart and of the source's
// gutters (which usually continue the chart), never another chart's: in a tight atlas the
// next chart sits a few texels away, and a resize may blend it in because it stays next
// door; a reshaped layout moves it. Where a triangle squeezes the source more than 3x
// in some direction (a target shrank it to almost nothing) the texel keeps the area bake's
// value: a kernel 3 new texels wide then spans 9+ source texels, far past the small source
// triangle, and averages unrelated detail into grey (CesiumMilkTruck's paper layout at half
// the texels: q 0.0059 with every texel Lanczos, 0.0030 with the cap, 0.0030 all area).
// Normal maps keep the area bake (their vectors must be rotated with the chart).
// Texels no triangle owns keep `area`'s values (gutters); covered texels are replaced and
// the gutter refilled from them (rebake's distance transform). With options.surround = r,
// the texels within r of a chart are baked too, through the map of the triangle that owns
// the nearest chart texel: a white-backed atlas (CesiumMilkTruck) blends white into its
// dark charts' edges at coarse mip levels, in the input as in a plain resize, and a gutter
// filled with the chart's own colour instead differed from the input at every chart edge
// (its repack at half the texels, 1024-px trilinear views: q 0.0231 against the resize's
// 0.0101; bilinear views, level 0 only: 0.0075 against 0.0071). Deterministic per texel.
#pragma once

#include "atlas/rebake.h"

namespace uvpress::atlas {

// `area`: rebake(source, meshes, options) (same size). Returns `area` as it is for normal
// maps. Throws like rebake() for an empty source or zero size.
// `baked`, when given (width * height), gets 1 for every texel this bake wrote.
Image rebake_lanczos(const Image& source, const std::vector<RebakeMesh>& meshes, const RebakeOptions& options,
                     const Image& area, std::vector<uint8_t>* baked = nullptr);

}  // namespace uvpress::atlas
