// `uvpress eval`: perceptual quality against pixel cost over 20 views (seed paper 001,
// section 5.1, eq. 20-23), for several UV layouts of one asset at once.
//
// - Cameras: 20, at the vertices of a regular dodecahedron around the mesh's bounding
//   sphere, looking at its centre, perspective (vertical field of view 30 degrees, the
//   sphere just inside the frame), square images of `resolution` pixels.
// - Resolution (auto, the default): views that resolve the reference texture. Texels per
//   screen pixel are measured per covered pixel of the 20 views at 512 px (isotropic: the
//   square root of a triangle's texel area over its screen area in that view); the side is
//   the smallest multiple of 16, at least 512, at which the `resolution_percentile` (95 %)
//   of the visible screen area is magnified or 1:1, capped at `resolution_cap` (2048: 20
//   reference views of 2048^2 floats are 320 MiB, and every render costs 16x a 512-px
//   one). Views wider than the engine's 1024-px limit are rendered in tiles (one camera a
//   tile) and stitched. Report: resolution, resolution_capped, texels_per_pixel (at the
//   percentile and the median, at the chosen side), resolved_fraction (share of the
//   visible screen area magnified or 1:1 there). A fixed --resolution reports the same.
//   At a side that resolves the texture, losing texels shows; at one that minifies it,
//   each pixel takes one sample of several texels and q is mostly aliasing pattern.
// - Renders: engine->render_mesh (CPU backend = oracle, Vulkan kernel render_mesh.comp).
//   Texture filter (`filter`): trilinear by default, as engines sample (the texture's mip
//   chain built as engines build it: box filter in linear light, see resize.h), so that
//   parts of the asset seen from afar are filtered rather than aliased; bilinear samples
//   level 0 only (the paper's renderer). Both in fp32 by hand, both backends alike.
// - Noise floor (report: noise_floor): how far q moves when only the sampling phase
//   does. The input resized to half its texels is scored as usual, again with the cameras
//   and the reference views shifted by a quarter pixel (two directions), and resized to
//   1, 2 and 3 texels more a side (the texel grid's phase; under 2 % more texels); the
//   largest change.
//   Differences in q below it are sampling phase, not texture, and are not claimed.
// - Reference: the input (first file) layout with its full texture, luminance.
// - Layouts: "input" (the reference's own UVs), with `paper_baseline` "input-rebaked" (the
//   same UVs, re-baked like every other layout: the paper's protocol, so figures can be set
//   beside the paper's), every other file (a glTF of the same mesh: reparam's output, an
//   xatlas or Blender layout), and with `flatten` the isometric layout ("flatten": charts
//   from the input's UV seams flattened by host/flatten's progressive solver, charts that
//   are not disks keep their input UVs scaled to their 3-D area, laid out on shelves at one
//   scale).
// - Each layout's full texture: the input's own; for every other layout, the reference
//   texture re-baked into its UVs (atlas::rebake) at the size where c_r = 1, when its triangles
//   correspond one to one with the reference's (same count, same corner positions);
//   otherwise the file's own texture.
// - Cost: image texels, what users pay for (every texel of the image in VRAM and on the
//   wire): c_r = W H / (W_ref H_ref), the reference's driving image. Each curve point also
//   carries the paper's c_r_chart (eq. 20-21: W H sum|uv triangle area|, texels under the
//   charts, relative to the reference's), which cannot see packing. For each c_r of the
//   grid the layout's texture keeps its aspect with W H = c_r W_ref H_ref (rounded).
// - Resize to that size: the input's texture as users' tools resize it, Lanczos-3
//   (resize.h), in stored sRGB values and in linear light, both evaluated, the one with the
//   lower mean log q over the grid kept (report: input_resize), so the baseline is the
//   strongest a user gets in one line; every other layout's full texture with that same
//   resize, so that curves differ by layout and not by filter (only "input-rebaked", the
//   paper's protocol, keeps the exact area (box) filter, bilinear when enlarging). Then the 20 views
//   are rendered and q = mean GMSD against the reference views (eq. 22-23). GMSD:
//   engine->gmsd for images up to 64 x 64, else engine/cpu/gmsd.h (fp32).
// - As written: every other file is also scored with its own texture at its real size and
//   its own sampler (what a user would see), beside its curve (report: as_written).
// - Savings: for a layout A against B, the ratio c_A(q) / c_B(q) of the costs at which the
//   two curves reach the same q, log-log interpolated, geometric mean over B's curve
//   points inside A's q range.
// - Codec (`codec`, `--codec astc-6x6`): the textures the curves and the as-written scores
//   sample are first compressed and decoded again, every mip level on its own (the chain
//   built from the uncompressed level 0, then each level compressed, as a texture farm
//   does), sRGB profile (the driving texture is a colour texture): q after the codec, so
//   that curves compare at equal compressed bytes (with one codec, bytes go with texels;
//   each curve point carries `codec_bytes`, its levels' blocks). The reference views and
//   the noise floor stay uncompressed. Lit: data maps (normal, occlusion, metallic-roughness)
//   go through astcenc's linear profile, colour maps through sRGB.
// - Shading (`shading`, report: shading "unlit" | "lit", shading_requested, and
//   shading_warning when auto fell back): unlit, q reads the driving texture's luminance;
//   lit (lit.h), q reads the luminance of the views lit by a fixed rig through the asset's
//   normal, occlusion / metallic-roughness and emissive maps, so that losing those maps'
//   detail shows. Lit layouts are every map sharing the driving texture's UVs: at each c_r
//   every map is resized by the same factor as the driving texture (colour maps by the
//   input's resize, data maps by the same filter on their stored values), re-baked layouts
//   re-bake every map (normal maps rotated into the new UV frame where tangents come from
//   the UVs). Missing maps take glTF's defaults. auto (the default): lit when a material of
//   the reference has a normalTexture, else unlit, so assets without normal maps keep
//   their figures bit for bit. When lit, every curve point and as_written carries q (the
//   lit q), q_unlit and q_lit, and the report noise_floor_unlit and noise_floor_lit beside
//   noise_floor (the lit one); the savings and the as-written scores (reparam's guard) use q.
#pragma once

#include "core/image.h"
#include "engine.h"
#include "io/astc_codec.h"
#include "io/gltf_io.h"
#include "lit.h"
#include "resize.h"
#include "result.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace uvpress::eval {

// How the views sample textures (see above; TextureFilter is in result.h).
std::optional<TextureFilter> parse_texture_filter(std::string_view text);

constexpr uint32_t kMaxResolution = 4096;  // views of more than 1024 px are tiled

struct EvalOptions {
  std::vector<double> cost_grid = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0};
  uint32_t resolution = 0;  // view images, pixels a side (8..kMaxResolution); 0: auto (see above)
  uint32_t resolution_cap = 2048;       // auto: the largest side (512..kMaxResolution)
  double resolution_percentile = 0.95;  // auto: share of the visible screen area to resolve
  TextureFilter filter = TextureFilter::Trilinear;
  bool noise_floor = true;  // measure and report the quarter-pixel noise floor (one more render)
  bool flatten = false;       // add the isometric layout
  bool paper_baseline = false;  // add "input-rebaked": the input layout re-baked like the others (§5.1)
  double contact_cost = 0;    // c_r of the contact sheet; 0: the grid point nearest 0.25
  uint32_t thumbnail = 160;   // contact sheet view size, pixels
  bool artifacts = true;      // keep what write_html_report needs (contact sheets, UV plots)
  double fov_degrees = 30;
  std::optional<io::AstcOptions> codec;  // q after ASTC compression (see above); none: uncompressed
  Shading shading = Shading::Auto;       // which q is q (see above)
};

// One layout to evaluate: a loaded glTF of the same mesh as the reference.
struct LayoutInput {
  std::string name;  // e.g. the file's stem
  const io::GltfFile* file = nullptr;
};

// Images kept for the HTML report (8-bit RGB as floats in Image).
struct LayoutArtifacts {
  std::string name;
  Image contact;  // the 20 views at the contact c_r, 5 x 4 thumbnails
  Image uv_plot;  // the layout in UV space coloured by relative texel density
};
struct EvalArtifacts {
  Image reference_contact;
  std::vector<LayoutArtifacts> layouts;
};

using Progress = std::function<void(const std::string& stage, size_t done, size_t total)>;

// Evaluates the reference's own layout ("input"), "input-rebaked" when
// options.paper_baseline, each of `others`, and the isometric layout when options.flatten:
// their curves, as-written scores and savings (result.h; `to_json` is the report the README
// describes). Throws InputError for assets without a textured triangle primitive or layouts
// of another mesh.
EvalResult evaluate(const io::GltfFile& reference, const std::vector<LayoutInput>& others, engine::Engine& engine,
                    const EvalOptions& options = {}, EvalArtifacts* artifacts = nullptr,
                    const Progress& progress = {});

// A candidate asset as written, scored against the reference: the 20 views of the
// candidate rendered with its own driving texture at its real size and its own sampler,
// q = mean GMSD against the reference's views (options: resolution, fov_degrees), c_r =
// candidate image texels / reference image texels (c_r_chart: the paper's texels under the
// charts, relative). The candidate need not share the reference's triangles, only its
// surface (the cameras frame the reference). reparam's "never worse" guard compares its
// result with a resized input this way. Throws InputError as evaluate does.
struct Scored {
  double c_r = 0, q = 0;  // q: the lit q when `lit`, else the unlit q
  double c_r_chart = 0;
  std::vector<float> q_views;  // GMSD per view (q is their mean)
  bool lit = false;
  double q_unlit = 0, q_lit = 0;  // both shadings when lit (q_lit 0 when unlit)
};
Scored score_as_written(const io::GltfFile& reference, const io::GltfFile& candidate, engine::Engine& engine,
                        const EvalOptions& options = {});

// The same, for many candidates against one reference: the reference's layout, cameras and
// 20 views are set up once (score_as_written sets them up per call). Not thread-safe.
class AsWrittenScorer {
 public:
  AsWrittenScorer(const io::GltfFile& reference, engine::Engine& engine, const EvalOptions& options = {});
  ~AsWrittenScorer();
  Scored score(const io::GltfFile& candidate);
  const ViewResolution& resolution() const;
  Shading shading() const;                    // Unlit or Lit: what `auto` resolved to
  const std::string& shading_warning() const;  // why auto fell back to unlit ("" otherwise)

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// Writes DIR/index.html (offline: no scripts, no network), DIR/plot.svg (log q_r against
// c_r by gnuplot when it is installed, each layout's as-written point marked; the report
// says when gnuplot is not installed), DIR/contact-*.png
// and DIR/uv-*.png. All files appear at once (temporaries renamed at the end). Throws
// InputError(dir, reason).
void write_html_report(const EvalResult& result, const EvalArtifacts& artifacts, const std::string& dir);

// --- Parts, exposed for tests ---

// 20 view-projection matrices (row-major, engine::MeshRenderDesc convention) around the
// bounding sphere of `positions`.
std::vector<std::array<float, 16>> dodecahedron_cameras(const float* positions, size_t vertex_count,
                                                        double fov_degrees = 30);

// A view's camera restricted to tile (a, b) of k x k (a from the left, b from the top):
// pixel (i, j) of the tile's render is pixel (a T + i, b T + j) of the whole view's, T the
// tile's side. How views wider than the engine's limit are rendered.
std::array<float, 16> tile_camera(const std::array<float, 16>& camera, uint32_t k, uint32_t a, uint32_t b);

// Savings of curve A against curve B: points (cost, q) by increasing cost. Returns the
// geometric mean ratio c_A / c_B at equal q and the number of q levels used (0: the
// curves' q ranges do not overlap; the ratio is then NaN). Where A's q at B's cost is
// within `noise_floor` of B's, the two cannot be told apart there and that level counts as
// a ratio of 1 (`ties`): on a curve flatter than the noise, equal-q costs are the noise's
// (Duck's curve moves 1.8e-4 from c_r 0.6 to 0.9 against a floor of 1.4e-4, and a tie read
// as "0.60x the pixels").
Savings pixel_ratio_at_equal_q(const std::vector<std::pair<double, double>>& a,
                               const std::vector<std::pair<double, double>>& b, double noise_floor = 0);
}  // namespace uvpress::eval
