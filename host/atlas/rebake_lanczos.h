// Lanczos re-bake: each new texel the Lanczos-3 filter of the source, warped by its
// triangle's affine map, so that a reshaped chart is resampled as sharply as a plain resize
// (at a uniform scale it is the Lanczos-3 resize itself). Values are filtered as stored,
// normalized and clamped to [0, 1]; a kernel reads its own chart and the source's gutters,
// never another chart; texels whose triangle squeezes the source more than 3x, and normal
// maps, keep the area bake. Sizes in texels; deterministic per texel. How the kernel is
// shaped and why, with measurements: the top of rebake_lanczos.cpp.
#pragma once

#include "atlas/rebake.h"

namespace uvpress::atlas {

// `area`: rebake(source, meshes, options) (same size). Returns `area` as it is for normal
// maps. Covered texels are re-baked and the gutter refilled from them; with
// options.surround = r, the texels within r of a chart are baked too (through the map of the
// triangle that owns the nearest chart texel); other texels keep `area`'s values. Throws
// like rebake() for an empty source or zero size.
// `baked`, when given (width * height), gets 1 for every texel this bake wrote.
Image rebake_lanczos(const Image& source, const std::vector<RebakeMesh>& meshes, const RebakeOptions& options,
                     const Image& area, std::vector<uint8_t>* baked = nullptr);

// The same bake with the area bake made on `engine` only for the texels that keep its value
// (squeezed or degenerate maps; every texel for normal maps or without the gutter fill):
// the result equals rebake_lanczos(source, meshes, options, rebake(source, meshes, options,
// engine)) texel for texel, and `stats` is rebake()'s with the texels this bake wrote added
// to its coverage. Filtering every texel by area first, to replace nearly all of them, was
// ~9 % of CesiumMilkTruck's reparam.
Image rebake_lanczos(const Image& source, const std::vector<RebakeMesh>& meshes, const RebakeOptions& options,
                     engine::Engine& engine, RebakeStats* stats = nullptr);

}  // namespace uvpress::atlas
