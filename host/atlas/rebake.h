// Re-baking a texture into new UVs (deterministic; the per-texel sampling on an engine).
//
// For every texel of the new image, the triangle that owns it is found among the new-UV
// triangles that overlap the texel's square (conservative rasterization): the one whose
// distance to the texel centre is smallest (0 when the centre is inside), ties to the
// lowest triangle index (meshes in order). The texel's footprint is mapped to the old
// texture by that triangle's affine map (barycentrics), and the old texture is sampled:
//
// Filter: box-filtered supersampling of bilinear samples. The new texel's square maps to a
// parallelogram in old texels with edges J e_x and J e_y (J = d old texel / d new texel);
// n_x = ceil(|J e_x|) by n_y = ceil(|J e_y|) samples (each at most max_samples) on a
// regular grid inside the new texel, each bilinear, averaged with equal weights. For an
// integer downscale this is the exact area (box) filter (a 2x2 reduction averages four
// texels exactly); at 1:1 or upscaling it is plain bilinear, so an identity re-bake is
// exact. Sample points are clamped into the owning triangle, so nothing is read from
// outside the source chart (the source's own gutter never bleeds in).
//
// Colour (sRGB-encoded) textures are filtered in linear light (decoded exactly through a
// table, re-encoded with the sRGB formula): averaging encoded values darkens edges and
// fine detail. Textures with alpha are filtered premultiplied (colour weighted by alpha,
// then divided), so invisible texels do not tint visible ones; alpha itself is filtered
// linearly and kept. Data textures (metallic-roughness, occlusion, ...) are filtered as
// stored.
//
// Normal maps (tangent-space, glTF: +X right, +Y up in the image, i.e. toward -v): the
// filtered vector n = 2 v - 1 has its xy rotated by the orthogonal polar factor of the
// triangle's Jacobian old -> new, taken in texel units and conjugated by diag(1, -1) for
// the v-down convention, then renormalized. This assumes square texels are square on the
// surface (the true tangent frame would need 3-D positions); for conformal layouts it is
// exact. When the Jacobian mirrors (det < 0) the factor is a reflection, which keeps xy
// correct relative to the new u/v axes (tangents' handedness is then the caller's).
//
// Gutter: texels covered by no triangle are filled for the mip chain (atlas/gutter_fill.h):
// a ring of the nearest chart texel's value, then each chart's colour extended through
// every mip level, so bilinear and mip sampling at chart borders sees chart colours,
// never background or (down to the level the gutter's width allows) a neighbour's.
#pragma once

#include "atlas/gutter_fill.h"
#include "core/image.h"
#include "engine.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace uvpress::atlas {

// One primitive's triangles with both UV sets (glTF convention: [0,1], v down, (0,0) the
// image's top-left corner). Both UV arrays are indexed by `indices`; any
// KHR_texture_transform must already be applied. Pointers must stay valid during rebake.
struct RebakeMesh {
  const uint32_t* indices = nullptr;
  size_t index_count = 0;  // 3 per triangle
  const float* old_uv = nullptr;  // u v per vertex
  const float* new_uv = nullptr;  // u v per vertex
  size_t vertex_count = 0;        // indices >= vertex_count are skipped
};

enum class RebakeRole {
  Color,   // RGB sRGB-encoded (baseColor, emissive); alpha linear
  Data,    // linear values (metallicRoughness, occlusion, masks)
  Normal,  // tangent-space normal map: RGB = (n + 1) / 2
};

// glTF sampler wrap modes.
constexpr int kWrapRepeat = 10497, kWrapClampToEdge = 33071, kWrapMirroredRepeat = 33648;

struct RebakeOptions {
  uint32_t width = 0, height = 0;  // the new image
  RebakeRole role = RebakeRole::Color;
  int wrap_s = kWrapRepeat, wrap_t = kWrapRepeat;  // the source's sampler
  bool linear_light = true;   // Color: filter in linear light (else in stored values)
  uint32_t max_samples = 16;  // per axis and texel
  bool fill_gutter = true;
  // Texels past each chart's edge (Chebyshev distance) that rebake_lanczos bakes from the
  // source through the nearest chart texel's triangle map, extended past the triangle: the
  // gutter then shows what the source has around the chart, and coarse mip levels blend it
  // in at the chart's edge as the input's own chain does (0: gutters only filled).
  uint32_t surround = 0;
};

struct RebakeStats {
  size_t covered = 0;            // texels owned by a triangle
  size_t triangles = 0;          // non-degenerate triangles rasterized
  std::vector<uint8_t> coverage; // width * height, 1 = covered (row 0 on top)
  double sample_seconds = 0;     // time in the per-texel sampling (on the engine)
};

// Same channel count and bit depth as `source`. Throws std::invalid_argument for an empty
// source or zero size.
//
// The host sets up and bins the triangles, picks owners, converts colour, rotates normals
// and fills gutters; the per-texel sampling runs on `engine` (engine::Engine::rebake_texels;
// a CPU engine, engine::make_cpu_engine, runs the double-precision oracle). Every engine
// gives the same coverage; texels agree to fp32 rounding (the Vulkan kernel works in fp32 in
// per-tile frames: see tests/atlas/test_rebake_engine.cpp for the stated tolerances).
Image rebake(const Image& source, const std::vector<RebakeMesh>& meshes, const RebakeOptions& options,
             engine::Engine& engine, RebakeStats* stats = nullptr);

// sRGB transfer functions (IEC 61966-2-1), exposed for tests and callers.
float srgb_to_linear(float v);
float linear_to_srgb(float v);

// The fast forms rebake uses: decode through the exact 16-bit table (exact for 8- and
// 16-bit values), encode by interpolation in a 16K table (error < 2e-6). Shared with
// rebake_lsq.cpp so both bakes convert identically.
float srgb_decode_fast(float v);
float srgb_encode_fast(float v);

// ---- The set-up of a re-bake, shared with rebake_lsq.cpp (one copy of each idea) ----
//
// Everything rebake() prepares before sampling: the working source (linear light and/or
// premultiplied for colour; empty when the stored values are used as they are), the
// triangles in texel units with their normal rotations, the tile bins (CSR, triangle
// order kept) and the owner of every texel (position in tile_list, kRebakeNoOwner where
// uncovered). `source` must outlive the plan.
struct RebakePlan {
  int width = 0, height = 0, channels = 0;
  bool has_alpha = false, linear = false, premultiplied = false;
  const Image* source = nullptr;
  std::vector<float> work;
  std::vector<engine::RebakeTriangle> triangles;
  std::vector<std::array<std::array<float, 2>, 2>> rotation;  // normal xy rotation old -> new, y-up
  std::vector<uint32_t> tile_start, tile_list, owner;
  // The engine's view of the plan (pointers into it and into *source).
  engine::RebakeTexelsDesc desc(const RebakeOptions& options) const;
};

// Throws like rebake() for an empty source or zero size.
RebakePlan plan_rebake(const Image& source, const std::vector<RebakeMesh>& meshes, const RebakeOptions& options);

}  // namespace uvpress::atlas
