// The real-client check (issue 12, part 3): reparam's outputs rendered by three.js in
// headless Chromium look, from every view, no worse than the plain Lanczos resize to the
// same texels plus a stated margin (client/client_check.h). Tag [client].
//
// Every asset is reparameterized with `--cost 0.5 --force-reparam`: the guard's choice is
// skipped so that the layout reparam built is what is checked (where the guard writes the
// resize, the output is the resize and passes trivially). The default suite runs the
// corrupted outputs (the comparison must catch them, the resize must pass against itself)
// the demo asset (`--evaluations 30`, ~50 s) and Duck; UVPRESS_CLIENT_FULL=1 runs the demo at
// reparam's defaults and adds Fox and CesiumMilkTruck, which fail today (see DEVELOPERS.md,
// "The real-client check").
// Renders and figures are kept in build/client-check/<asset>/ (render.png: rows input,
// output, resize, coverage mask; figures.json).
#include "client/client_check.h"

#include "atlas/rebake.h"
#include "io/asset.h"
#include "io/gltf_io.h"
#include "io/image_io.h"
#include "pipeline/demo_asset.h"
#include "support.h"

#include <catch2/catch.hpp>

#include <chrono>
#include <cstdlib>
#include <fstream>

using namespace uvpress;
namespace client = uvpress::test::client;

namespace {

bool full_run() {
  const char* v = std::getenv("UVPRESS_CLIENT_FULL");
  return v && std::string(v) == "1";
}

test::fs::path artifacts(const std::string& name) {
  test::fs::path p = test::fs::path(UVPRESS_BINARY_DIR) / "client-check" / name;
  test::fs::remove_all(p);
  test::fs::create_directories(p);
  return p;
}

// Why the check cannot run here, if it cannot.
std::optional<std::string> cannot_run() {
  if (auto why = client::chromium_unavailable()) return "Chromium cannot render WebGL here: " + *why;
  return std::nullopt;
}

struct Checked {
  client::Verdict verdict;
  std::vector<client::ViewDiff> output, resize;
};

// The input as a .glb (images byte for byte): the page reads one file per model.
void to_glb(const test::fs::path& input, const test::fs::path& glb) {
  auto copied = test::run_uvpress("copy '" + input.string() + "' -o '" + glb.string() + "'");
  INFO(copied.err);
  REQUIRE(copied.exit_code == 0);
}

// Renders input, output and the resize to the output's texels; judges; keeps the figures and
// the render in build/client-check/<name>/.
Checked judge_pair(const std::string& name, const test::fs::path& in, const test::fs::path& out,
                   const test::Scratch& dir, nlohmann::json figures) {
  const test::fs::path keep = test::fs::path(UVPRESS_BINARY_DIR) / "client-check" / name;
  test::fs::create_directories(keep);
  const auto resize = dir / "resize.glb";
  const auto t1 = std::chrono::steady_clock::now();
  const nlohmann::json resized = client::write_resize(in, out, resize);
  REQUIRE(!resized.empty());  // the output shrank something
  const client::Render R = client::render({in, out, resize}, dir / "chromium");
  const auto t2 = std::chrono::steady_clock::now();
  Checked c;
  c.output = client::compare(R, 1, 0);
  c.resize = client::compare(R, 2, 0);
  c.verdict = client::judge(c.output, c.resize);
  for (auto& [k, v] : c.verdict.json.items()) figures[k] = v;
  figures["asset"] = name;
  figures["resized_images"] = resized;
  figures["render"] = {{"status", R.status}, {"attempts", R.attempts}};
  figures["seconds"]["render"] = std::chrono::duration<double>(t2 - t1).count();
  std::ofstream(keep / "figures.json") << figures.dump(2) << "\n";
  const auto png = io::encode_image(R.image, "png");
  std::ofstream(keep / "render.png", std::ios::binary).write(reinterpret_cast<const char*>(png.data()), std::streamsize(png.size()));
  // Most views see the asset (a one-sided sheet is empty from behind).
  size_t judged = 0;
  for (const auto& d : c.output) judged += d.covered >= client::kMinCovered;
  CHECK(judged >= 6);
  return c;
}

// reparam `input` (a .gltf or .glb) at --cost 0.5, then judge_pair.
Checked check_asset(const std::string& name, const test::fs::path& input) {
  const auto t0 = std::chrono::steady_clock::now();
  test::Scratch dir("client-" + name);
  const test::fs::path keep = artifacts(name);
  const auto in = dir / "input.glb", out = dir / "output.glb";
  to_glb(input, in);
  const std::string settings = full_run() ? "" : " --evaluations 30";
  auto r = test::run_uvpress("reparam '" + in.string() + "' -o '" + out.string() + "' --cost 0.5 --force-reparam" +
                             settings + " --report '" + (keep / "reparam.json").string() + "'");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  nlohmann::json figures;
  figures["reparam"] = "--cost 0.5 --force-reparam" + settings;
  figures["seconds"]["reparam"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return judge_pair(name, in, out, dir, figures);
}

std::string failures(const client::Verdict& v) {
  std::string s;
  for (const auto& f : v.failures) s += "  " + f + "\n";
  return s;
}

void check_passes(const std::string& name, const test::fs::path& input) {
  const Checked c = check_asset(name, input);
  INFO("figures: build/client-check/" << name << "/figures.json\nfailing views:\n" << failures(c.verdict));
  CHECK(c.verdict.pass);
}

std::optional<test::fs::path> shared_asset(const std::string& rel) {
  auto dir = test::shared_dir();
  if (!dir) return std::nullopt;
  auto p = *dir / "assets" / rel;
  if (!test::fs::exists(p)) return std::nullopt;
  return p;
}

}  // namespace

TEST_CASE("client: the demo asset's reparam output renders in three.js as well as a plain resize", "[client]") {
  // Passes at the mip-safe gutter (2026-12-07: with `--evaluations 30` and at the defaults),
  // with one view on the margin (far-az45-el70, p99 38 against the resize's 30 + 8); it
  // failed two far views when reparam's reshaped layout had 4-texel gutters. A wider
  // default gutter for small images failed three (DEVELOPERS.md, "The real-client check").
  if (auto why = cannot_run()) UVPRESS_SKIP(*why);
  test::Scratch dir("client-demo-asset");
  io::save_gltf(pipeline::make_demo_asset(), (dir / "demo.glb").string());
  check_passes("demo", dir / "demo.glb");
}

TEST_CASE("client: Duck's reparam output renders in three.js as well as a plain resize", "[client][shared]") {
  // Passes since reparam aligns its kept plan at the wide gutter too (2026-12-08): the layout
  // kept, unit-scale+least-squares+wide-gutter+mip-aligned-deep (16 texels, sides multiples
  // of 32; eval's q 0.00017 against the resize's 0.0010), is within the resize's p99 + 2 in
  // every view (distant-az45-el30 20 / 18, distant-az225-el10 15 / 16, far-az90-el20 2 / 9).
  // Its 8-texel twin, kept before, let the eye unit's white bleed into the wing's and the
  // back's edges at the coarse levels the distant views sample (p99 43 / 20 and 56 / 12) and
  // failed three views. ~40 s on 2 cores.
  auto duck = shared_asset("Duck/glTF/Duck.gltf");
  if (!duck) UVPRESS_SKIP("../shared/assets/Duck is absent");
  if (auto why = cannot_run()) UVPRESS_SKIP(*why);
  check_passes("Duck", *duck);
}

TEST_CASE("client: Fox's reparam output renders in three.js as well as a plain resize, no seams far away",
          "[client][shared][full]") {
  if (!full_run()) UVPRESS_SKIP("Fox's real-client check runs with UVPRESS_CLIENT_FULL=1 (minutes on 2 cores)");
  auto fox = shared_asset("Fox/glTF/Fox.gltf");
  if (!fox) UVPRESS_SKIP("../shared/assets/Fox is absent");
  if (auto why = cannot_run()) UVPRESS_SKIP(*why);
  const Checked c = check_asset("Fox", *fox);
  INFO("figures: build/client-check/Fox/figures.json\nfailing views:\n" << failures(c.verdict));
  CHECK(c.verdict.pass);
  // Issue 12: the seams gone at a distance — in the far and distant views the output's
  // 99th percentile is at most the resize's, no margin.
  for (size_t i = 0; i < c.output.size(); ++i) {
    const bool far = c.output[i].kind == "far" || c.output[i].kind == "distant";
    if (!far || c.output[i].covered < client::kMinCovered) continue;
    INFO(c.output[i].view << ": output p99 " << c.output[i].p99 << ", resize p99 " << c.resize[i].p99);
    CHECK(c.output[i].p99 <= c.resize[i].p99);
  }
}

TEST_CASE("client: CesiumMilkTruck's reparam output renders in three.js as well as a plain resize",
          "[client][shared][full]") {
  if (!full_run()) UVPRESS_SKIP("CesiumMilkTruck's real-client check runs with UVPRESS_CLIENT_FULL=1 (minutes on 2 cores)");
  auto truck = shared_asset("CesiumMilkTruck/glTF/CesiumMilkTruck.gltf");
  if (!truck) UVPRESS_SKIP("../shared/assets/CesiumMilkTruck is absent");
  if (auto why = cannot_run()) UVPRESS_SKIP(*why);
  check_passes("CesiumMilkTruck", *truck);
}

// The test of the test: outputs with a known defect fail. They are made from the plain
// resize of the demo asset (no reparam needed), which passes against itself exactly: a
// grey square where a chart's texels were (content wrong, as the truck's headlight), and
// the whole texture moved by 1/64 of its side (every chart on the wrong texels).
TEST_CASE("client: deliberately corrupted outputs fail the three.js comparison", "[client]") {
  if (auto why = cannot_run()) UVPRESS_SKIP(*why);
  test::Scratch dir("client-corrupted");
  const auto in = dir / "input.glb", half = dir / "half.glb", resize = dir / "resize.glb";
  const auto square = dir / "square.glb", shifted = dir / "shifted.glb";
  io::save_gltf(pipeline::make_demo_asset(), in.string());
  // A stand-in output: the input at half the texels (the resize of that is itself).
  client::edit_image(in, half, 0, [](Image& img) {
    const uint32_t w = img.width, h = img.height;
    Image small;
    small.width = uint32_t(std::lround(w / std::sqrt(2.0)));
    small.height = uint32_t(std::lround(h / std::sqrt(2.0)));
    small.channels = img.channels;
    small.bits = img.bits;
    small.pixels.resize(size_t(small.width) * small.height * small.channels);
    for (uint32_t y = 0; y < small.height; ++y)  // nearest texel: any shrink will do
      for (uint32_t x = 0; x < small.width; ++x)
        for (uint32_t c = 0; c < img.channels; ++c)
          small.at(x, y, c) = img.at(x * w / small.width, y * h / small.height, c);
    img = small;
  });
  client::write_resize(in, half, resize);
  client::edit_image(resize, square, 0, [](Image& img) {
    const uint32_t s = img.width / 8, x0 = img.width / 2 - s / 2, y0 = img.height / 2 - s / 2;
    for (uint32_t y = y0; y < y0 + s; ++y)
      for (uint32_t x = x0; x < x0 + s; ++x)
        for (uint32_t c = 0; c < std::min(3u, img.channels); ++c) img.at(x, y, c) = 0.5f;
  });
  client::edit_image(resize, shifted, 0, [](Image& img) {
    const Image src = img;
    const uint32_t dx = std::max(1u, img.width / 64), dy = std::max(1u, img.height / 64);
    for (uint32_t y = 0; y < img.height; ++y)
      for (uint32_t x = 0; x < img.width; ++x)
        for (uint32_t c = 0; c < img.channels; ++c)
          img.at(x, y, c) = src.at((x + dx) % img.width, (y + dy) % img.height, c);
  });
  const auto keep = artifacts("corrupted");
  const client::Render R = client::render({in, resize, square, shifted}, dir / "chromium");
  const auto png = io::encode_image(R.image, "png");
  std::ofstream(keep / "render.png", std::ios::binary).write(reinterpret_cast<const char*>(png.data()), std::streamsize(png.size()));
  const auto base = client::compare(R, 1, 0);
  nlohmann::json figures;
  // The resize against itself passes (zero margin used).
  const auto self = client::judge(base, base);
  CHECK(self.pass);
  int row = 2;
  for (const char* what : {"square", "shifted"}) {
    const auto v = client::judge(client::compare(R, row++, 0), base);
    figures[what] = v.json;
    INFO(what << ": failing views:\n" << failures(v));
    CHECK_FALSE(v.pass);
    CHECK(v.failures.size() >= 2);  // seen from more than one view
  }
  std::ofstream(keep / "figures.json") << figures.dump(2) << "\n";
}

// A tool more than a test (hidden: not in the suite): judges any input and output,
// UVPRESS_CLIENT_INPUT and UVPRESS_CLIENT_OUTPUT (.gltf or .glb), named UVPRESS_CLIENT_NAME
// (default "pair"); the figures go to build/client-check/<name>/. E.g.
//   UVPRESS_CLIENT_INPUT=in.gltf UVPRESS_CLIENT_OUTPUT=out.glb build/tests/uvpress_client_tests '[client-pair]'
TEST_CASE("client: judge a given input and output", "[.][client-pair]") {
  const char* in = std::getenv("UVPRESS_CLIENT_INPUT");
  const char* out = std::getenv("UVPRESS_CLIENT_OUTPUT");
  if (!in || !out) UVPRESS_SKIP("set UVPRESS_CLIENT_INPUT and UVPRESS_CLIENT_OUTPUT");
  if (auto why = cannot_run()) UVPRESS_SKIP(*why);
  const char* name_env = std::getenv("UVPRESS_CLIENT_NAME");
  const std::string name = name_env ? name_env : "pair";
  test::Scratch dir("client-pair");
  artifacts(name);
  to_glb(in, dir / "input.glb");
  to_glb(out, dir / "output.glb");
  nlohmann::json figures;
  figures["input"] = in;
  figures["output"] = out;
  const Checked c = judge_pair(name, dir / "input.glb", dir / "output.glb", dir, figures);
  INFO("figures: build/client-check/" << name << "/figures.json\nfailing views:\n" << failures(c.verdict));
  CHECK(c.verdict.pass);
}

// A diagnostic (hidden): how much of an output's difference from the input is the input's
// own gutter bleeding. The input's images are re-baked into the input's own UVs (at 1:1 an
// exact copy of every chart texel) with the gutters filled as reparam fills them
// (atlas/gutter_fill.h): the "clean input". Rows: input, output, resize, clean input; per
// view the 99th percentiles of output, resize and clean input against the input, and of
// output and resize against the clean input, go to build/client-check/<name>/clean.json.
//   UVPRESS_CLIENT_INPUT=in.gltf UVPRESS_CLIENT_OUTPUT=out.glb build/tests/uvpress_client_tests '[client-clean]'
TEST_CASE("client: the output against the input with its gutters filled", "[.][client-clean]") {
  const char* in = std::getenv("UVPRESS_CLIENT_INPUT");
  const char* out = std::getenv("UVPRESS_CLIENT_OUTPUT");
  if (!in || !out) UVPRESS_SKIP("set UVPRESS_CLIENT_INPUT and UVPRESS_CLIENT_OUTPUT");
  if (auto why = cannot_run()) UVPRESS_SKIP(*why);
  const char* name_env = std::getenv("UVPRESS_CLIENT_NAME");
  const std::string name = name_env ? name_env : "clean";
  test::Scratch dir("client-clean");
  const test::fs::path keep = test::fs::path(UVPRESS_BINARY_DIR) / "client-check" / name;
  test::fs::create_directories(keep);
  to_glb(in, dir / "input.glb");
  to_glb(out, dir / "output.glb");
  client::write_resize(dir / "input.glb", dir / "output.glb", dir / "resize.glb");
  io::GltfFile f = io::load_gltf((dir / "input.glb").string());
  const io::Asset asset = io::build_asset(f);
  for (const io::AssetImage& img : asset.images) {
    std::vector<atlas::RebakeMesh> meshes;
    for (const io::ImageUse& use : img.uses) {
      const io::Primitive& p = asset.primitives[size_t(use.primitive)];
      if (size_t(use.tex_coord) >= p.uv_sets.size()) continue;
      const float* uv = p.uv_sets[size_t(use.tex_coord)].uv.data();
      meshes.push_back({p.indices.data(), p.indices.size(), uv, uv, p.vertex_count()});
    }
    if (meshes.empty()) continue;
    auto& bytes = f.image_bytes.at(size_t(img.index));
    const Image source = io::decode_image(bytes, "image");
    atlas::RebakeOptions ro;
    ro.width = source.width, ro.height = source.height;
    ro.role = img.color_space == ColorSpace::Srgb ? atlas::RebakeRole::Color : atlas::RebakeRole::Data;
    ro.wrap_s = img.uses.front().wrap_s, ro.wrap_t = img.uses.front().wrap_t;
    const Image clean = atlas::rebake(source, meshes, ro, test::cpu_engine());
    bytes = io::encode_image(clean, io::sniff_image_format(bytes.data(), bytes.size()) == "jpeg" ? "jpeg" : "png");
  }
  io::save_gltf(f, (dir / "clean.glb").string());
  const client::Render R = client::render({dir / "input.glb", dir / "output.glb", dir / "resize.glb", dir / "clean.glb"}, dir / "chromium");
  const auto png = io::encode_image(R.image, "png");
  std::ofstream(keep / "clean.png", std::ios::binary).write(reinterpret_cast<const char*>(png.data()), std::streamsize(png.size()));
  const auto out_in = client::compare(R, 1, 0), resize_in = client::compare(R, 2, 0), clean_in = client::compare(R, 3, 0);
  const auto out_clean = client::compare(R, 1, 3), resize_clean = client::compare(R, 2, 3);
  nlohmann::json views = nlohmann::json::array();
  for (size_t i = 0; i < out_in.size(); ++i) {
    if (out_in[i].covered < client::kMinCovered) continue;
    views.push_back({{"view", out_in[i].view},
                     {"p99", {{"output_vs_input", out_in[i].p99}, {"resize_vs_input", resize_in[i].p99},
                              {"clean_vs_input", clean_in[i].p99}, {"output_vs_clean", out_clean[i].p99},
                              {"resize_vs_clean", resize_clean[i].p99}}}});
  }
  std::ofstream(keep / "clean.json") << nlohmann::json{{"input", in}, {"output", out}, {"views", views}}.dump(2) << "\n";
  CHECK(!views.empty());
}
