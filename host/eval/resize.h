// Resizing a texture as users' tools do: the baselines eval (and reparam's guard) compare
// a layout against. Images are core/image.h: values as stored in [0,1], interleaved;
// colour textures sRGB-encoded.
#pragma once

#include "core/image.h"

#include <cstdint>
#include <vector>

namespace uvpress::eval {

// Resizes to width x height: exact box filter per axis when shrinking, linear
// interpolation (texel centres, clamp) when enlarging; the same size copies exactly.
// Filters the stored values, every channel alike. The paper's protocol (seed 001 §5.1)
// and eval's re-baked layouts use it: it never rings and keeps the mean exactly.
Image resize_area(const Image& image, uint32_t width, uint32_t height);

// Resizes to width x height with a separable Lanczos-3 filter, placed and normalized as
// OpenImageIO's ImageBufAlgo::resize "lanczos3" does (support 3 output texels when
// shrinking, 3 input texels when enlarging, weights normalized, taps past the border read
// the edge texel; agrees with it to 2e-5, its float rounding), what `gltf-transform
// resize`, `gltfpack -ts` and image editors do, so the baseline a user would compare
// against. Weights per axis in double, two passes, OpenMP over rows (same bits on any
// thread count). linear_light: colour channels (grey, or RGB; never alpha) are decoded
// sRGB -> linear before and encoded after, as a careful tool does; false filters the
// stored (sRGB) values, as most tools do. Alpha is filtered as stored and colours are not
// premultiplied (transparent texels bleed their colour, as they do in those tools).
// Results are clamped to [0,1]: Lanczos rings at edges. The same size copies exactly.
// Throws std::runtime_error for an empty image or size.
Image resize_lanczos3(const Image& image, uint32_t width, uint32_t height, bool linear_light);

// The mip chain an engine builds for a colour texture (glGenerateMipmap on an sRGB
// texture): `levels` images, level 0 the image itself and level l of max(1, W >> l) x
// max(1, H >> l) texels, each the exact box (area) filter of the level above in linear
// light (colour channels decoded before and encoded after, alpha as stored), as
// glGenerateMipmap builds it. What eval's trilinear views sample. colour = false: a data
// texture (normal, occlusion, metallic-roughness), every channel boxed as stored.
std::vector<Image> mip_chain(const Image& image, uint32_t levels, bool colour = true);

}  // namespace uvpress::eval
