// `uvpress reparam`: the whole perceptual-loss re-parameterization of an asset (seed
// paper 001): per UV layout shared by a set of textures, the triangle stage (GP-BO of each
// triangle's Jacobian on the engine), the mesh stage per chart, packing into the budget,
// re-baking every texture that samples the layout, and the new UVs and images written into
// the glTF. Everything else in the file is kept as it is.
#pragma once

#include "core/texture_cost.h"
#include "engine.h"
#include "eval/eval.h"
#include "flatten/flatten.h"
#include "io/gltf_io.h"
#include "io/gltf_prune.h"
#include "perceptual/triangle_stage.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace uvpress::pipeline {

// Which algorithm wrote an output: raised by every change that changes reparam's outputs
// for the same input and options (layouts, bakes, gutters, encoders), so that a resumed
// batch redoes what an older algorithm wrote (batch compares it with the options).
constexpr int kReparamRevision = 21;  // 2: image-edge gutters by sampler, surround in gutters; 3: equal-slope candidates, least squares keeps the surround; 4: the wide-gutter variant; 5: normal-mapped assets scored lit (candidates, guard); 6: the unit-scale candidate, wide gutters for the best other plan too; 7: scoring views rolled to the asset and capped at 2560 where the cap binds (the truck); 8: below half the texels, the allocating plans also with the half's allocation; 9: the view bake's CG stops on its render error (triangle-stage scores move by ~1e-5); 10: the triangle stage stops stalled searches by default; 11: atlas shapes between 1:2 and 2:1 of the source's (steps of 2^(1/4) to 2^(1/16), the largest chart's own); 12: never a texel over an image-texel budget; 13: the +mip-aligned variants; 14: GMSD sums of eval-sized views in interleaved lanes; 15: replaced UVs leave the bufferViews they shared; 16: truecolour PNGs re-baked as a palette where it is faithful; 17: the gutter fill continues a surround for as far again (atlas::fill_ring); 18: the +mip-aligned variants keep their copies at the source density (ChartShape::pinned); 19: a paletted input's texture drawn from its own palette, PNG rows deflated by libdeflate; 20: atlas sides multiples of the gutter's power of two, gutters flat where no mip level reads them near a chart (atlas::coarsen_gutter), a new palette fitted to the charts first; 21: the kept plan aligned at both gutters, the guard's resize also at sides multiples of the layout's, eval's curve sides even (--max-gmsd sizes)

struct ReparamOptions {
  double cost = 0.5;       // relative pixel cost c_r of the new textures vs the old (eq. 20-21)
  uint32_t size = 0;       // instead of cost: the new size of the largest side of the driving texture
  bool power_of_two = false;
  // The new textures keep the source's aspect ratio. Otherwise the packer may choose 2:1,
  // 1:2 (or 4:1, 1:4) of it when that holds the charts at a larger scale (atlas/pack.h).
  bool keep_aspect = false;
  // Texels between charts (the image edges get half of it where a sampler repeats, else none: atlas::edge_gutter). kAutoGutter: mip-safe for the image's size
  // (atlas::mip_safe_gutter: every mip level clean down to the first of side <= 64 texels,
  // at most 16: 8 texels for a 362^2 image, 16 from 1024^2 on).
  static constexpr uint32_t kAutoGutter = UINT32_MAX;
  uint32_t gutter = kAutoGutter;
  uint32_t block = 1;      // chart alignment (4 for BCn)
  bool optimize = true;    // false: keep every Jacobian (identity), only repack and re-bake
  // Instead of a cost: the smallest textures whose 20-view quality (eval, mean GMSD against
  // the input) is at most this. The layout is made at the source density, evaluated on a
  // cost grid, and its re-baked textures are area-filtered down to the cheapest size that
  // meets the bound (gutters shrink with them). 0: off.
  double max_gmsd = 0;
  // Rate control (with optimize, --cost or --size): each triangle's GMSD bound is
  // max(rate_margin * its loss under the plain resize to the requested cost, rate_floor)
  // instead of the fixed triangle.epsilon (which --epsilon restores).
  bool rate_control = true;
  double rate_margin = 1.25;
  double rate_floor = 1e-4;
  // Build a few candidate layouts (the paper's targets, floored stretches, a plain repack)
  // and keep the one whose written file scores best over eval's 20 views.
  bool candidates = true;
  // Before writing, compare the result with the input resized (Lanczos-3) to the same
  // texels by the same 20-view score, and write the better (--force-reparam: false).
  bool guard = true;
  // With candidates: also re-bake the kept layout by least squares and keep the better.
  bool least_squares_bake = true;
  // Charts that keep their shape keep their texels: copied from the source resized to the
  // layout's scale (Lanczos-3), whole-texel placements (atlas/place_texels.h).
  bool exact_texels = true;
  // When not empty (bench quality, demo): reparam's own q-c curve, the report's `curve`
  // [{c_r, q, layout}]: at each of these costs the best of the kept plan and the best other
  // base plan, each at both gutters when the gutter is automatic, the second-best other
  // base plan at the default gutter, and the +mip-aligned variants reparam made, each built into that budget
  // with the shapes made for the requested cost, and scored as written (a cost where every
  // plan has new UV overlaps gets no point, with a warning).
  std::vector<double> curve_costs;
  // The views candidates, the guard, --max-gmsd and the curve are scored with: eval's
  // resolution (0: auto) and texture filter (host/eval/eval.h).
  uint32_t score_resolution = 0;
  eval::TextureFilter score_filter = eval::TextureFilter::Trilinear;
  // Their shading (eval::Shading): auto lights assets with normal maps, so the guard sees
  // what a layout does to them.
  eval::Shading score_shading = eval::Shading::Auto;
  perceptual::TriangleStageOptions triangle;
  // `flatten --assign`: one layout, the isometric one (pipeline/isometric_charts.h) instead
  // of the triangle stage's targets: every chart that can be flattened (by `flatten`'s
  // options), charts sharing source texels each given texels of their own, at one texel
  // density; then packed into --cost and re-baked like any layout, scored as written when
  // `guard` or the scorer allows (the guard itself is not applied: the user asked for these
  // UVs). No triangle stage, no other candidates.
  bool isometric = false;
  flatten::Options flatten;
};

// Progress: stage name, done, total (for a stderr bar on long runs).
using Progress = std::function<void(const std::string& stage, size_t done, size_t total)>;

// One candidate layout as built and scored as written (report: candidates[]).
struct CandidateScore {
  std::string name;
  double cost_ratio = 1;    // new image texels / old
  double q = -1;            // 20-view q as written; < 0: not scored
  size_t overlaps_new = 0;  // > 0: disqualified, never written
  // Wall seconds: mesh stage, packing, re-bake (every image), scoring as written.
  double seconds_mesh = 0, seconds_pack = 0, seconds_bake = 0, seconds_score = 0;
};

// The never-worse guard (report: guard): the kept layout against the input resized
// (Lanczos-3) to the same texels, by the same 20-view q; the better is written.
struct Guard {
  bool ran = false;
  std::string skipped;  // why eval could not score the asset, when it could not
  double q_reparam = -1, q_resize = -1;
  std::string chosen;   // "reparam" | "resize"
  // The resize scored (the better of two): its sides multiples of reparam's image's
  // (LayoutReport::side_multiple) rather than at the nearest size.
  bool resize_aligned = false;
  // Re-baked images that the scoring views do not render (their layout is not the driving
  // image's: MultiUVTest's emissive map on TEXCOORD_1), by name: neither q sees them.
  std::vector<std::string> unseen;
  // Both files scored again from afar (eval's cameras, views of `resolution` pixels a side:
  // coarse mip levels, gutters and the packing's neighbours show there). Said, not chosen
  // on: none when the guard's near views were set by --score-resolution at or below it.
  struct Far {
    uint32_t resolution = 0;
    double q_reparam = -1, q_resize = -1;
    double noise_floor = 0;  // eval's quarter-pixel noise floor at these views: closer q are a tie
  };
  std::optional<Far> far;
};

// --max-gmsd (report: max_gmsd): the cheapest point of the layout's curve that meets the bound.
struct MaxGmsd {
  double bound = 0;
  bool met = false;
  double c_r = 1, q = 0;
  double scale = 1;  // of every re-baked texture
};

// One UV set of a layout (report: layouts[].uv_sets[]): TEXCOORD_<tex_coord> of glTF mesh
// `mesh`'s primitive `primitive`.
struct UvSetReport {
  int mesh = -1, primitive = -1, tex_coord = 0;
};

// The equal-slope allocation of a layout's optimized triangles at the requested cost, or at
// half the texels for a `+half-allocation` candidate (report: layouts[].equal_slope;
// perceptual/rate_allocation.h).
struct EqualSlopeReport {
  double cost = 0;        // share of the source's texels under the triangles
  double spent = 0;       // sum a_t s_t^2 / sum a_t at the solution
  double multiplier = 0;  // the Lagrange multiplier mu
  std::array<double, 3> scale_quartiles{};  // of the triangles' isotropic scales
};

// The `unit-scale` candidate's scales per packing unit (report: layouts[].unit_scale).
struct UnitScaleReport {
  double cost = 0;   // the allocation's share of the units' source texels
  size_t units = 0;  // packing units
  std::array<double, 3> scale_quartiles{};  // of the units' scales, the largest 1
  double scale_min = 0;
};

// The isometric layout's charts (report: layouts[].isometric; pipeline/isometric_charts.h).
struct IsometricReport {
  size_t charts_flattened = 0, charts_kept = 0;  // kept: the input shape
  size_t holes_filled = 0;                       // boundary loops closed for the solves
  double texels_per_area = 0;                    // the common density, texels per unit of 3-D area
};

// Reshaped charts re-embedded in their input outline (report: layouts[].outline).
struct OutlineReport {
  size_t kept = 0;         // charts re-embedded in their input outline
  size_t failed = 0;       // ... where that folded or overlapped: the mesh stage's shape
  double mean_blend = 0;   // over the kept ones (perceptual::OutlineFit::blend)
};

// What the triangle stage measured over a layout (report: layouts[].triangle_stage).
struct TriangleStageReport {
  // The GMSD bound: the fixed epsilon, or under rate control (rate_control set, written
  // instead of it) the per-triangle bounds' quartiles and maximum.
  double epsilon = 0;
  struct RateControl {
    std::array<double, 3> quartiles{};
    double max = 0;
  };
  std::optional<RateControl> rate_control;
  int evaluations = 0;     // per triangle: the cap
  double evaluations_mean = 0;  // spent per triangle (below the cap where early_stop ended searches)
  bool early_stop = false;
  uint32_t view_size = 0;  // pixels a view side
  size_t triangles = 0;    // through the triangle stage
  size_t feasible = 0;     // some evaluation met epsilon
  size_t infeasible = 0;   // none did: kept at the identity
  size_t views_resolve_texels = 0;  // every view at most one source texel a pixel
  size_t sampled_by_patches = 0;    // large triangles seen through a sample of patches
  size_t tiles_coarsened = 0;       // views whose tile took a coarser lattice at J = I
  std::array<double, 3> lambda_area_quartiles{};  // lambda1 lambda2 of the targets
  // The infeasible triangles' loss at the identity, when there are any.
  struct IdentityGmsd {
    double median = 0, max = 0;
  };
  std::optional<IdentityGmsd> infeasible_identity_gmsd;
};

// One UV layout of the file (report: layouts[i], layout i of the file). An untouched layout
// has only images, driver, uv_sets and untouched; a re-parameterized one has the rest
// (the optional ones only where their candidate or options made them).
struct LayoutReport {
  std::vector<int> images;  // image indices that sample it
  int driver = -1;          // the image whose perceptual loss drives the optimization
  std::vector<UvSetReport> uv_sets;
  std::optional<std::string> untouched;  // why the layout is left as it is
  std::optional<EqualSlopeReport> equal_slope;  // equal-slope candidates
  std::optional<UnitScaleReport> unit_scale;    // the unit-scale candidate
  std::optional<IsometricReport> isometric;     // flatten --assign
  double pack_seconds = 0;
  size_t charts = 0, rigid_charts = 0;  // rigid: mixed orientation, moved, not reshaped
  size_t shared_texel_charts = 0;       // packed with the charts they share texels with, unreshaped
  size_t packing_units = 0;
  size_t exact_units = 0;   // units whose texels are copied, not resampled
  // Of them, those packed at the source's density while the other units took the packing's
  // scale (`scale`): the +mip-aligned variants' copies, where they fit so.
  size_t pinned_units = 0;
  size_t exact_texels = 0;  // texels copied (over every image of the layout)
  std::array<uint32_t, 2> atlas{};  // the driver's new size, texels
  double scale = 0;         // the packing scale, new texels per source texel (pinned units: 1)
  double scale_cap = 0;     // the source density of the densest triangles
  bool capped_at_source_density = false;  // scale reached scale_cap
  double packing_efficiency = 0;  // share of the image's texels under charts
  uint32_t gutter = 0;            // texels between charts
  uint32_t mip_align = 1;         // copies' translations multiples of it (a +mip-aligned candidate)
  uint32_t side_multiple = 1;     // the atlas's sides multiples of this (every candidate but under --size)
  std::array<uint32_t, 2> edge_gutter{};  // texels at the left/right and top/bottom edges
  double gutter_texels = 0;       // texels kept empty around charts and at the edges
  double footprint_texels = 0;    // texels under the charts' footprints (covered ones and their rims: atlas::Packing)
  double chart_cost_ratio = 0;    // eq. 21: texels under the charts / the input's
  size_t flips = 0;
  size_t overlaps_new = 0;             // triangle pairs; 0, or the layout is not written
  size_t overlap_fallback_charts = 0;  // reshaped charts that ran over themselves: input shape
  size_t overlap_fallback_pairs = 0;   // the new overlapping pairs they would have had
  std::optional<OutlineReport> outline;  // outline candidates
  // With the triangle stage (optimize): charts whose mesh-stage factorization failed (kept
  // unreshaped), and what the stage measured.
  std::optional<size_t> mesh_stage_failed_charts;
  std::optional<TriangleStageReport> triangle_stage;
};

// One re-baked image (report: textures[]): its sizes, bytes and costs as written, and the
// bytes of the input resized to the same size (texture_costs.h).
struct TextureReport {
  int image = -1;
  std::string name;
  std::string role;  // its first use's (io::to_string(TextureRole)), "other" when unused
  std::array<uint32_t, 2> old_size{}, new_size{};  // texels (new: the resize's when the guard wrote it)
  uint64_t old_bytes = 0, new_bytes = 0;           // encoded
  // Set by reparam's texture costs, in every report.
  std::string encoding;  // io::describe of the input's encode settings
  std::string written;   // what the new bytes are (io::describe_encoded): a palette where it was faithful
  TextureCost old_cost, new_cost;  // report: old, new (with old_bytes, new_bytes)
  uint64_t resize_bytes = 0;       // the input Lanczos-3-resized to new_size, encoded the same way
  double bytes_ratio = 0;          // new_bytes / old_bytes
  double bytes_vs_resize = 0;      // new_bytes / resize_bytes
};

struct StageSeconds {
  std::optional<double> max_gmsd_eval;  // --max-gmsd's curve
  double texture_costs = 0, triangle_stage = 0, mesh_stage = 0, pack = 0, rebake = 0;
  double candidates_and_guard = 0;  // scoring candidates and the resize as written
  double score_far = 0;             // of which the views from afar (Guard::Far)
  double candidates_built = 0;      // building every candidate (mesh stage, packing, re-bakes), the kept one too
};

// What reparam did to the file; to_json is the --report docs/DEVELOPERS.md lists under
// `uvpress reparam`.
struct ReparamResult {
  engine::DeviceInfo device;
  // The views candidates and the guard were scored with, when they were.
  struct Scoring {
    eval::ViewResolution resolution;
    eval::TextureFilter filter = eval::TextureFilter::Trilinear;
    eval::Shading shading = eval::Shading::Unlit;
  };
  std::optional<Scoring> scoring;
  // With ReparamOptions::curve_costs: at each cost (by their order; none where every plan
  // had new UV overlaps) the plan that scored best there as written, its c_r and q.
  struct CurvePoint {
    double c_r = 0, q = 0;
    std::string layout;
  };
  std::optional<std::vector<CurvePoint>> curve;
  // The curve as (c_r, q) points (eval::pixel_ratio_at_equal_q); empty without one.
  std::vector<std::pair<double, double>> curve_cost_q() const;
  std::optional<MaxGmsd> max_gmsd;
  // Every re-baked texture's costs, before and after, and the bytes the input resized to
  // the same size would take (texture_costs.h).
  struct TextureTotals {
    TextureCost old_cost, new_cost;
    uint64_t old_bytes = 0, new_bytes = 0, resize_bytes = 0;
  } texture_totals;
  io::PruneResult pruned;
  std::string chosen;  // "reparam", "resize" or "untouched"
  std::string layout;  // the kept candidate's name
  std::vector<CandidateScore> candidates;
  Guard guard;
  std::optional<double> q;  // the written file's 20-view q, when scored
  // Per UV layout and per re-baked texture, the details the README lists (sizes, scales,
  // packing, triangle-stage counts, bytes); layouts[i] is layout i of the file.
  std::vector<LayoutReport> layouts;
  std::vector<TextureReport> textures;
  double cost_ratio = 1;  // new image texels / old over the re-baked textures
  size_t flips = 0, overlaps_new = 0, overlap_fallback_charts = 0, charts = 0;
  size_t triangles_optimized = 0, triangles_infeasible = 0;
  StageSeconds stages;
  std::vector<std::string> warnings;
  double seconds = 0;

  // True when some layout was capped at the source's texel density (a cost above what the
  // source holds).
  bool capped_at_source_density() const;
  nlohmann::ordered_json to_json() const;
};

// Re-parameterizes `file` in place (model and image_bytes): the layouts found, each
// prepared (charts, triangle stage), the candidate layouts built and scored, the best
// kept, the guard against a plain resize, --max-gmsd, the costs, and what the replacement
// left unused pruned. `layout_out`, when given, receives reparam's kept layout as built
// even when the guard writes the resize (bench quality's re-baked ratios evaluate it).
ReparamResult reparam(io::GltfFile& file, engine::Engine& engine, const ReparamOptions& options,
                      const Progress& progress = {}, io::GltfFile* layout_out = nullptr);

}  // namespace uvpress::pipeline
