// The real-client check (issue 12, part 3): what a user's viewer shows. Input, output and
// the plain resize a user would do instead are rendered with three.js's GLTFLoader in
// headless Chromium (SwiftShader WebGL), unlit, mip-mapped, from a fixed set of views
// (tests/client/render.mjs: 6 far, 2 distant, 4 near, 4 close-ups), and compared per view:
//
//   output passes a view when  mean(|output - input|) <= mean(|resize - input|) + kMeanMargin
//                         and  p99(|output - input|)  <= p99(|resize - input|)  + kP99Margin
//
// over the pixels the input covers in that view (its coverage mask), where |a - b| is a
// pixel's largest absolute difference over R, G, B in 8-bit display values (0–255), and
// "resize" is the input with each image the output shrank Lanczos-3-resized (stored values,
// as gltf-transform resize does) to the same texels at its own aspect ratio: the loss a
// user already accepts when asking for that many texels. The margins are stated in
// kMeanMargin and kP99Margin below.
#pragma once

#include "core/image.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace uvpress::test::client {

namespace fs = std::filesystem;

// Margins over the resize's difference, in 8-bit levels. The mean's: 1 level — a shift of
// the average error by 1/255 is below what anyone sees, while a wrong region moves a
// view's mean by more (a grey square on 1/64 of the demo's texture: +6 in the close-up
// that sees it; a texture moved by 1/64: +5 to +17). The 99th percentile's: 8 levels — the
// worst 1 % of pixels sits on edges and fine detail, where a reparameterized layout
// legitimately trades sharpness with the resize texel by texel (the demo's own layout: at
// most +4), but a seam line, a bled gutter or a wrong texture region puts that 1 % tens of
// levels off (CesiumMilkTruck's tyres and Fox's back seen from afar: +20 to +60).
constexpr double kMeanMargin = 1.0;
constexpr double kP99Margin = 8.0;

// Tile size in pixels of each view.
constexpr int kTile = 256;

// A view in which the input covers fewer pixels than this is reported, not judged: its
// 99th percentile would be a handful of silhouette pixels.
constexpr size_t kMinCovered = 400;

// Why Chromium cannot render WebGL here (absent, does not start, no WebGL context), or
// nothing when it can. Tried once per process.
std::optional<std::string> chromium_unavailable();

// tools/node_modules/three, installed by tools/install-deps.sh.
bool three_installed();

struct View {
  std::string name, kind;  // render.mjs's: kind far, distant, near or close
};

struct Render {
  Image image;  // (columns × tile) × (rows × tile), RGBA, row r = model r, the last row the mask
  int tile = 0, rows = 0, columns = 0;
  std::vector<View> views;  // one a column
  int attempts = 0;     // Chromium runs it took (a black or failed frame is run again)
  std::string status;   // the page's status line
};

// Renders the .glb files (one row each, cameras fitted to the first) and the first file's
// coverage mask. Throws std::runtime_error with the page's or Chromium's words when three
// attempts fail. `work` holds Chromium's profile and logs.
Render render(const std::vector<fs::path>& glbs, const fs::path& work, int tile = kTile);

struct ViewDiff {
  std::string view, kind;  // render.mjs's view name and kind
  size_t covered = 0;      // pixels the input covers
  double mean = 0, p99 = 0;
};

// Per view: the differences between row `a` and row `b` over the mask row's covered pixels.
std::vector<ViewDiff> compare(const Render& r, int a, int b);

// The input with every image that the output resized Lanczos-3-resized to the same texels
// at its own aspect ratio (the resize reparam's guard compares with), written as a .glb.
// Returns the images resized as [{image, from, to}].
nlohmann::json write_resize(const fs::path& input_glb, const fs::path& output_glb, const fs::path& resize_glb);

// Output vs resize, per view: the figures and the verdict.
struct Verdict {
  nlohmann::json json;  // {views: [{view, kind, covered, output {mean, p99}, resize {mean, p99}, pass}], pass}
  bool pass = true;
  std::vector<std::string> failures;  // "view: output mean M p99 P vs resize mean m p99 p"
};
Verdict judge(const std::vector<ViewDiff>& output, const std::vector<ViewDiff>& resize);

// Writes a copy of `glb` whose image `image` went through `edit` (re-encoded in its format):
// the deliberately corrupted outputs of the test of the test.
void edit_image(const fs::path& glb, const fs::path& out_glb, int image, const std::function<void(Image&)>& edit);

}  // namespace uvpress::test::client
