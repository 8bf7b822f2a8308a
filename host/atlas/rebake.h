// Re-baking a texture into new UVs: every texel of the new image takes the mean of bilinear
// samples of the source over its footprint, mapped back through the triangle that owns it
// (an area filter: exact at integer downscales, plain bilinear at 1:1 and above, so an
// identity re-bake is exact). Colour is filtered in linear light, alpha premultiplied,
// normal maps rotated with their chart; gutters are filled for the mip chain. UVs in glTF's
// convention ([0,1], v down), sizes in texels. Deterministic; the per-texel sampling runs on
// an engine. How texels are owned, filtered, converted and rotated: the top of rebake.cpp.
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

// The nearest-texel ring of the gutter fill after a bake with these options
// (atlas::fill_gutter's `ring`): as wide as the surround, so that free space next to a
// chart continues what lies at the surround's outer edge for as far again before the
// pull-push takes over; one texel without a surround.
inline uint32_t fill_ring(const RebakeOptions& options) { return options.surround > 1 ? options.surround : 1; }

struct RebakeStats {
  size_t covered = 0;            // texels owned by a triangle
  size_t triangles = 0;          // non-degenerate triangles rasterized
  std::vector<uint8_t> coverage; // width * height, 1 = covered (row 0 on top)
  // width * height, 1 = a triangle overlaps the texel: the charts' footprints alone, without
  // the surround or texels copied later (what atlas::coarsen_gutter keeps).
  std::vector<uint8_t> footprint;
  double sample_seconds = 0;     // time in the per-texel sampling (on the engine)
};

// Same channel count and bit depth as `source`. Throws std::invalid_argument for an empty
// source or zero size. `only`, when given (width * height): only the texels it marks are
// filtered; the other covered texels are 0, yet covered (rebake_lanczos, which replaces
// them, asks for the few it keeps).
//
// The host sets up and bins the triangles, picks owners, converts colour, rotates normals
// and fills gutters; the per-texel sampling runs on `engine` (engine::Engine::rebake_texels;
// a CPU engine, engine::make_cpu_engine, runs the double-precision oracle). Every engine
// gives the same coverage; texels agree to fp32 rounding (the Vulkan kernel works in fp32 in
// per-tile frames: see tests/atlas/test_rebake_engine.cpp for the stated tolerances).
Image rebake(const Image& source, const std::vector<RebakeMesh>& meshes, const RebakeOptions& options,
             engine::Engine& engine, RebakeStats* stats = nullptr, const std::vector<uint8_t>* only = nullptr);

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
