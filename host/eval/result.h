// What `eval::evaluate` measured, as types: per layout its q-c curve (q = mean GMSD over
// the 20 views against the reference, eq. 22-23; c_r in image texels relative to the
// reference's driving image, with the paper's chart texels of eq. 20-21 beside it), the
// as-written score of every other file, and the pixel savings between curves. `to_json`
// is eval's --report (README, "CLI reference"); callers read fields, never keys.
#pragma once

#include "engine.h"
#include "io/astc_codec.h"
#include "lit.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace uvpress::eval {

// How the views sample textures: trilinear (mip-mapped, as engines do) or bilinear
// (level 0 only, the paper's renderer).
enum class TextureFilter { Bilinear, Trilinear };
const char* to_string(TextureFilter filter);

// What the curves' cost counts: image texels (W x H of the driving texture, relative to the
// reference's), or bytes (the driving texture encoded as the reference's image is: its
// codec, palette, JPEG quality and subsampling, relative to the reference image's bytes).
enum class CostAxis { Texels, Bytes };
const char* to_string(CostAxis axis);

// The view resolution an evaluation chose and what it resolves (eval.h, "Resolution").
struct ViewResolution {
  uint32_t resolution = 512;  // pixels a side of the whole view
  bool automatic = false, capped = false;
  bool cropped = false;        // views rolled and cropped to the asset's screen rectangle (where the cap binds)
  double view_pixels = 0;      // pixels rendered a view, on average
  double percentile = 0.95;
  double texels_per_pixel = 0;         // at the percentile, at `resolution`
  double texels_per_pixel_median = 0;  // at `resolution`
  double resolved_fraction = 0;        // visible screen area with <= 1 texel per pixel
  double noise_floor = 0;              // quarter-pixel jitter q (0 when not measured)
};

// One layout scored at one cost: its texture W x H, q over the views.
struct CurvePoint {
  double c_r = 0;         // the grid's cost, image texels relative to the reference
  double c_r_actual = 0;  // W H / reference image texels, after rounding W and H
  double c_r_chart = 0;   // texels under the charts, relative (eq. 20-21)
  uint32_t width = 0, height = 0;
  double q = 0;                   // the lit q when lit, else the unlit q
  double q_unlit = 0, q_lit = 0;  // both, when lit
  std::vector<float> q_views;     // GMSD per view (q is their mean)
  std::optional<uint64_t> codec_bytes;  // with a codec: the mip chain's compressed blocks
  // CostAxis::Bytes: the texture's encoded bytes (as written: the file's own image), and
  // those relative to the reference image's bytes (the cost the savings compare).
  std::optional<uint64_t> bytes;
  double bytes_ratio = 0;
};

// One layout's curve and where it came from.
struct LayoutResult {
  std::string name, file;
  std::string texture;  // "original", "rebaked", "own"
  uint32_t full_size[2] = {0, 0};
  double uv_area = 0;
  double texel_density_spread_log2 = 0;
  nlohmann::ordered_json isometric;  // the isometric layout's flatten summary (null otherwise)
  std::optional<std::string> rebake;  // how the full texture was re-baked, when it was
  std::string resize;                // the filter that brings the full texture to each c_r
  // The input: mean log q of both user resizes over the grid (the better one is kept).
  std::optional<std::pair<double, double>> resize_mean_log_q;  // (sRGB, linear)
  // Other files: scored with their own texture at its real size and their own sampler
  // (c_r is the real cost; c_r_actual is not used).
  std::optional<CurvePoint> as_written;
  std::vector<CurvePoint> curve;  // by the grid's order (increasing c_r)

  // (c_r_actual, q) by increasing cost, or on the bytes axis (bytes_ratio, q) for the points
  // no cheaper point of the curve matches or beats in q: what eval's savings compare.
  std::vector<std::pair<double, double>> cost_q(CostAxis axis = CostAxis::Texels) const;
  // (c_r, q) at the grid's costs, in its order: what curves of written costs (reparam's
  // `curve`) are compared with.
  std::vector<std::pair<double, double>> grid_q() const;
};

// Curve A against curve B (eval.h, pixel_ratio_at_equal_q).
struct Savings {
  double ratio = 0;
  size_t points = 0;
  size_t ties = 0;  // levels within the noise floor, counted as ratio 1
  double q_lo = 0, q_hi = 0;
};
struct SavingsRow {
  std::string layout, vs;
  Savings savings;
};

struct EvalSeconds {
  double textures = 0, render = 0, gmsd = 0, shading = 0;  // shading: lit views on the host
  double total = 0;
};

struct EvalResult {
  std::string asset;
  engine::DeviceInfo device;
  size_t views = 0;
  ViewResolution resolution;
  uint32_t resolution_cap = 0;
  bool noise_floor_measured = false;  // false: noise_floor is reported as null
  double fov_degrees = 0;
  TextureFilter filter = TextureFilter::Trilinear;
  bool lit = false;
  Shading shading_requested = Shading::Auto;
  std::string shading_warning;  // why auto fell back to unlit ("" otherwise)
  double noise_floor_unlit = 0, noise_floor_lit = 0;  // when lit and measured
  size_t triangles = 0;
  struct Reference {
    std::string file;
    int image = -1;
    uint32_t width = 0, height = 0;
    double uv_area = 0, image_texels = 0, chart_texels = 0;
    uint64_t image_bytes = 0;  // the driving image's encoded bytes in the file
    std::string encoding;      // CostAxis::Bytes: how every texture is encoded (io::describe)
  } reference;
  CostAxis cost_axis = CostAxis::Texels;
  std::optional<io::AstcOptions> codec;
  std::vector<double> cost_grid;
  double contact_c_r = 0;
  std::string input_resize;  // "lanczos3-srgb" | "lanczos3-linear"
  std::vector<LayoutResult> layouts;
  std::vector<SavingsRow> savings;
  EvalSeconds seconds;

  // The noise floor as used for ties: 0 when not measured.
  double noise_floor() const { return noise_floor_measured ? resolution.noise_floor : 0.0; }
  // The layout called `name`, or nullptr.
  const LayoutResult* layout(const std::string& name) const;
  nlohmann::ordered_json to_json() const;
};

}  // namespace uvpress::eval
