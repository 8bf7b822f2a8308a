// Charts that keep their shape keep their texels: copying instead of resampling.
//
// A chart moved only by a whole-texel translation and quarter turns (atlas::ChartShape::snap)
// and scaled by exactly the factor of an image resized beforehand needs no resampling: each
// of its atlas texels is one texel of that resized image. `reparam` resizes the source once
// (Lanczos-3, as a user's resize would) to the layout's scale, packs unreshaped charts
// snapped to that image's grid, and copies their texels over the re-bake: at scale 1 an
// unreshaped chart is then bit-exact, and below 1 it looks exactly like the plain resize
// (no second filter, no bilinear shift), so a repack never loses to the resize it competes
// with except where it has fewer texels.
#pragma once

#include "atlas/pack.h"
#include "core/image.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace uvpress::atlas {

// Copies, into `atlas`, the texels of chart `index` of `packing`: every atlas texel whose
// square overlaps one of `shape`'s triangles (conservative, as the packer's footprint),
// dilated by `dilation` texels so that bilinear taps at the chart's border read the source's
// own neighbours too, takes the texel of `resized` that the placement maps onto it. The
// chart's points times its placement's scale must be in `resized`'s texel units and the placement a
// whole-texel translation (snap), with `resized` and `atlas` of the same channel count.
// Texels that map outside `resized` are left as they are. Returns the number copied; when
// `copied` is given (atlas width * height bytes) every texel written is set to 1 in it, so
// that the gutter can be refilled from the copies (atlas/gutter_fill.h).
size_t copy_chart_texels(const Image& resized, const ChartShape& shape, const Packing& packing, size_t index,
                         uint32_t dilation, Image& atlas, std::vector<uint8_t>* copied = nullptr);

}  // namespace uvpress::atlas
