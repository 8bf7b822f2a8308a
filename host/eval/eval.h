// `uvpress eval`: perceptual quality against pixel cost over 20 views (seed paper 001,
// section 5.1, eq. 20-23), for several UV layouts of one asset at once.
//
// For each layout, at each relative cost c_r of a grid (image texels W H relative to the
// reference's driving image; the paper's chart texels beside it), its texture is brought to
// that size and the 20 views around the mesh are rendered; q = the mean GMSD of those views
// against the reference's (the input layout with its full texture), lower is better. The
// layouts: the input resized as users' tools do (the baseline), every other file given
// (re-baked from the reference when its triangles are the reference's), and optionally the
// paper's baseline and the isometric layout; each other file is also scored as written.
// Savings compare curves at equal q. How each of these is measured (view resolution, the
// noise floor, the resizes, codecs, lit shading) is written at the top of eval.cpp; the
// result's fields are in result.h.
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

// How the views sample textures (eval.cpp, "Renders"; TextureFilter is in result.h).
std::optional<TextureFilter> parse_texture_filter(std::string_view text);
// "texels" | "bytes" (result.h, CostAxis).
std::optional<CostAxis> parse_cost_axis(std::string_view text);

constexpr uint32_t kMaxResolution = 4096;  // views of more than 1024 px are tiled

struct EvalOptions {
  std::vector<double> cost_grid = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0};
  uint32_t resolution = 0;  // view images, pixels a side (8..kMaxResolution); 0: auto (eval.cpp, "Resolution")
  uint32_t resolution_cap = 2560;       // auto: the largest side (512..kMaxResolution); where it binds, views
                                        // are rolled and cropped to the asset at cap^2 pixels a view on average
                                        // (eval.cpp)
  double resolution_percentile = 0.95;  // auto: share of the visible screen area to resolve
  TextureFilter filter = TextureFilter::Trilinear;
  bool noise_floor = true;  // measure and report the quarter-pixel noise floor (one more render)
  bool flatten = false;       // add the isometric layout
  bool paper_baseline = false;  // add "input-rebaked": the input layout re-baked like the others (§5.1)
  double contact_cost = 0;    // c_r of the contact sheet; 0: the grid point nearest 0.25
  uint32_t thumbnail = 160;   // contact sheet view size, pixels
  bool artifacts = true;      // keep what write_html_report needs (contact sheets, UV plots)
  double fov_degrees = 30;
  std::optional<io::AstcOptions> codec;  // q after ASTC compression (eval.cpp, "Codec"); none: uncompressed
  CostAxis cost_axis = CostAxis::Texels;  // what the savings compare at equal q (eval.cpp, "Cost axis")
  Shading shading = Shading::Auto;       // which q is q (eval.cpp, "Shading")
  // The image whose primitives the views draw (glTF image index); -1: the base colour
  // sampled by the most triangles (layout.h, extract_layout). Reference and candidates alike.
  int driving_image = -1;
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
  // The glTF image the views render (the reference's driving texture, extract_layout): only
  // the primitives that sample it are scored, so a change to another image's layout is not seen.
  int driving_image() const;

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

// A view's camera restricted to the window of w x h pixels whose top-left corner is pixel
// (x0, y0) of the whole view of `side` x `side` pixels (x from the left, y from the top):
// pixel (i, j) of the window's render is pixel (x0 + i, y0 + j) of the whole view's. How
// views are cropped to the asset where the resolution cap binds; tile_camera is the window
// (a, b, 1, 1) of a k x k view.
std::array<float, 16> window_camera(const std::array<float, 16>& camera, double side, double x0, double y0, double w,
                                    double h);

// A view's camera rolled about its axis by `angle` radians: what the view shows is the same,
// its image turned counter-clockwise by `angle` about the view's centre (NDC x, y rotated;
// the views are square and isotropic, so nothing is stretched).
std::array<float, 16> roll_camera(const std::array<float, 16>& camera, double angle);

// The roll (radians, in (-pi/4, pi/4]) under which the asset's screen rectangle, the
// bounding box of its projected vertices in `camera`'s view, is smallest: the minimum-area
// rectangle of their convex hull, one of whose sides lies on a hull edge (Freeman and
// Shapira 1975). How cropped views hold an oblique elongated asset (the truck seen from a
// dodecahedron vertex) in fewer pixels. 0 for fewer than 3 distinct points or a vertex
// behind the eye.
double asset_roll(const float* positions, size_t vertex_count, const std::array<float, 16>& camera);

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
