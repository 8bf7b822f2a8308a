// reparam end to end on real assets: valid output, nothing flipped, textures that look
// the same through the new UVs, and what must stay untouched does.
#include <catch2/catch.hpp>

#include "engine.h"
#include "eval/eval.h"
#include "eval/resize.h"
#include "io/asset.h"
#include "io/asset_bytes.h"
#include "io/gltf_append.h"
#include "io/gltf_io.h"
#include "io/image_io.h"
#include "pipeline/demo_asset.h"
#include "pipeline/reparam.h"
#include "support.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <set>

using namespace uvpress;
namespace fs = std::filesystem;

namespace {

// Bilinear sample (clamp to edge) of channel c at UV (glTF convention).
float sample(const Image& img, float u, float v, uint32_t c) {
  float s = std::min(std::max(u * img.width - 0.5f, 0.0f), float(img.width - 1));
  float t = std::min(std::max(v * img.height - 0.5f, 0.0f), float(img.height - 1));
  uint32_t i0 = uint32_t(s), j0 = uint32_t(t), i1 = std::min(i0 + 1, img.width - 1), j1 = std::min(j0 + 1, img.height - 1);
  float fs = s - float(i0), ft = t - float(j0);
  return (1 - ft) * ((1 - fs) * img.at(i0, j0, c) + fs * img.at(i1, j0, c)) +
         ft * ((1 - fs) * img.at(i0, j1, c) + fs * img.at(i1, j1, c));
}

// Mean absolute difference between the old texture through the old UVs and the new
// texture through the new UVs, at random points inside every triangle of `primitive`
// (away from triangle edges, where gutters and seams live).
double surface_difference(const io::GltfFile& before, const io::GltfFile& after, size_t primitive, int tex_coord,
                          int image) {
  io::Asset a = io::build_asset(before), b = io::build_asset(after);
  Image ta = io::decode_image(before.image_bytes[size_t(image)], "before");
  Image tb = io::decode_image(after.image_bytes[size_t(image)], "after");
  const auto& pa = a.primitives[primitive];
  const auto& ua = pa.uv_sets[size_t(tex_coord)].uv;
  const auto& ub = b.primitives[primitive].uv_sets[size_t(tex_coord)].uv;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> r(0.15f, 0.7f);
  double sum = 0;
  size_t n = 0;
  for (size_t t = 0; t < pa.triangle_count(); ++t) {
    float w1 = r(rng), w2 = r(rng) * (1 - w1) * 0.8f + 0.1f * (1 - w1), w0 = 1 - w1 - w2;
    const uint32_t* f = &pa.indices[3 * t];
    float u0 = w0 * ua[2 * f[0]] + w1 * ua[2 * f[1]] + w2 * ua[2 * f[2]];
    float v0 = w0 * ua[2 * f[0] + 1] + w1 * ua[2 * f[1] + 1] + w2 * ua[2 * f[2] + 1];
    float u1 = w0 * ub[2 * f[0]] + w1 * ub[2 * f[1]] + w2 * ub[2 * f[2]];
    float v1 = w0 * ub[2 * f[0] + 1] + w1 * ub[2 * f[1] + 1] + w2 * ub[2 * f[2] + 1];
    for (uint32_t c = 0; c < std::min(3u, ta.channels); ++c) sum += std::abs(sample(ta, u0, v0, c) - sample(tb, u1, v1, c));
    ++n;
  }
  return sum / double(n * std::min(3u, ta.channels));
}

pipeline::ReparamOptions keep_shapes(double cost = 1.0) {
  pipeline::ReparamOptions o;
  o.optimize = false;
  o.cost = cost;
  return o;
}

// The shared Duck (glTF with its .bin and PNG beside it); the caller skips without ../shared.
io::GltfFile shared_duck() {
  return io::load_gltf((*test::shared_dir() / "assets" / "Duck" / "glTF" / "Duck.gltf").string());
}

// Duck with its texture stored as an RGB PNG instead of its 54-colour palette: the same
// texels, written back as a truecolour input's are (a palette only where faithful), so that
// a test of how reparam allocates or guards is not also a test of the palette's loss.
io::GltfFile truecolour(io::GltfFile f) {
  for (auto& bytes : f.image_bytes) bytes = io::encode_image(io::decode_image(bytes, "image"), "png");
  return f;
}

// A candidate's q and cost ratio from reparam's report (q -1: not built).
std::pair<double, double> candidate_score(const nlohmann::ordered_json& report, const std::string& name) {
  for (const auto& c : report["candidates"])
    if (c["name"] == name) return {c["q"].get<double>(), c["cost_ratio"].get<double>()};
  return {-1.0, 0.0};
}

// The best q among a report's +mip-aligned candidates and how many were scored (1 when none).
std::pair<double, size_t> best_aligned(const nlohmann::ordered_json& report) {
  double q = 1;
  size_t n = 0;
  for (const auto& c : report["candidates"])
    if (c["name"].get<std::string>().find("+mip-aligned") != std::string::npos && c["q"].get<double>() > 0)
      q = std::min(q, c["q"].get<double>()), ++n;
  return {q, n};
}

// reparam of the shared Duck with `o`: the input, the file written and the result.
struct DuckRun {
  io::GltfFile in, out;
  pipeline::ReparamResult result;
  nlohmann::ordered_json report;
};
DuckRun reparam_duck(engine::Engine& engine, const pipeline::ReparamOptions& o, bool rgb = false) {
  DuckRun r{rgb ? truecolour(shared_duck()) : shared_duck(), {}, {}, {}};
  r.out = r.in;
  r.result = pipeline::reparam(r.out, engine, o);
  r.report = r.result.to_json();
  return r;
}

// eval of `in` alone at `cost`: its resize there (layouts[0]) and its noise floor.
eval::EvalResult input_at(const io::GltfFile& in, engine::Engine& engine, double cost) {
  eval::EvalOptions eo;
  eo.artifacts = false;
  eo.cost_grid = {cost};
  return eval::evaluate(in, {}, engine, eo);
}

}  // namespace

TEST_CASE("reparam without optimization at the same cost: the textures look the same through the new UVs",
          "[pipeline][reparam][shared]") {
  if (!test::shared_dir()) UVPRESS_SKIP("../shared is absent");
  auto engine = engine::make_cpu_engine({});
  io::GltfFile in = io::load_gltf((*test::shared_dir() / "assets/Duck/glTF-Binary/Duck.glb").string());
  io::GltfFile out = in;
  auto report = pipeline::reparam(out, *engine, keep_shapes(1.0)).to_json();
  CHECK(report["flips"] == 0);
  // Bilinear resampling at about the same density: a small, stated tolerance.
  CHECK(surface_difference(in, out, 0, 0, 0) < 0.02);
}

TEST_CASE("reparam on the demo asset: smaller texture, nothing flipped, valid, detail kept", "[pipeline][reparam]") {
  auto engine = engine::make_cpu_engine({});
  io::GltfFile in = pipeline::make_demo_asset({24, 256});
  io::GltfFile out = in;
  pipeline::ReparamOptions o;
  o.cost = 0.5;
  o.triangle.evaluations = 16;
  o.triangle.view_size = 16;
  const pipeline::ReparamResult result = pipeline::reparam(out, *engine, o);
  auto report = result.to_json();
  CHECK(report["flips"] == 0);
  CHECK(report["cost_ratio"].get<double>() <= 0.5 + 0.02);
  CHECK(result.textures.size() == 1);
  test::Scratch dir("reparam-demo");
  io::save_gltf(out, (dir / "demo.glb").string());
  CHECK(test::validate_gltf(dir / "demo.glb")["numErrors"] == 0);
  // At half the texels the surface still looks close to the original.
  CHECK(surface_difference(in, out, 0, 0, 0) < 0.08);
}

TEST_CASE("reparam keeps shared assets valid and leaves tiled and transformed layouts alone", "[pipeline][reparam][shared]") {
  if (!test::shared_dir()) UVPRESS_SKIP("../shared is absent");
  auto engine = engine::make_cpu_engine({});
  test::Scratch dir("reparam-shared");
  for (const char* rel : {"Duck/glTF/Duck.gltf", "CesiumMilkTruck/glTF/CesiumMilkTruck.gltf", "MultiUVTest/glTF/MultiUVTest.gltf",
                          "TextureTransformTest/glTF/TextureTransformTest.gltf", "BoxTextured/glTF/BoxTextured.gltf",
                          "Fox/glTF/Fox.gltf"}) {
    INFO(rel);
    auto path = *test::shared_dir() / "assets" / rel;
    io::GltfFile in = io::load_gltf(path.string());
    io::GltfFile out = in;
    auto o = keep_shapes(0.5);
    o.score_resolution = 512;  // validity, not quality: fixed views (the auto ones cost 4-16x)
    const pipeline::ReparamResult result = pipeline::reparam(out, *engine, o);
    auto report = result.to_json();
    CHECK(report["flips"] == 0);
    auto target = dir / (path.stem().string() + ".glb");
    io::save_gltf(out, target.string());
    auto before = test::validate_gltf(path), after = test::validate_gltf(target);
    for (auto& [code, count] : after["errors"].items()) CHECK(count.get<int>() <= before["errors"].value(code, 0));
    CHECK(after["numErrors"].get<int>() <= before["numErrors"].get<int>());
    CHECK(after["codes"].value("UNUSED_OBJECT", 0) <= before["codes"].value("UNUSED_OBJECT", 0));
    // Never heavier than the input (Fox: its replaced UVs leave the bufferView they shared).
    CHECK(io::asset_bytes(target.string()).total() <= io::asset_bytes(path.string()).total());
    io::Asset a = io::build_asset(in), b = io::build_asset(out);
    const std::string name = rel;
    if (name.rfind("BoxTextured", 0) == 0 || name.rfind("TextureTransformTest", 0) == 0) {
      // Untouched: same UVs, same image bytes, a warning saying why.
      // (TextureTransformTest's marker images, sampled without a transform, are re-laid.)
      CHECK(a.primitives[0].uv_sets[0].uv == b.primitives[0].uv_sets[0].uv);
      CHECK(in.image_bytes[0] == out.image_bytes[0]);
      CHECK(report["warnings"].size() >= 1);
    } else {
      CHECK(report["cost_ratio"].get<double>() <= 0.52);
      CHECK(surface_difference(in, out, 0, 0, a.images[0].index) < 0.1);
    }
    if (name.rfind("CesiumMilkTruck", 0) == 0) {
      // One atlas for both materials: the truck body and the wheels both read it correctly.
      REQUIRE(out.image_bytes.size() == 1);
      CHECK(surface_difference(in, out, 3, 0, 0) < 0.1);
    }
    if (name.rfind("MultiUVTest", 0) == 0) {
      CHECK(result.layouts.size() == 2);  // TEXCOORD_0 (baseColor) and TEXCOORD_1 (emissive) separately
      CHECK(surface_difference(in, out, 0, 1, 1) < 0.1);
    }
  }
}

TEST_CASE("reparam's scoring draws a layout it changes, and names the re-baked images its views do not draw",
          "[pipeline][reparam][shared]") {
  // TextureTransformTest: eval's views draw the primitives of the most-sampled base colour,
  // 'UV.png', which is sampled through KHR_texture_transform and so left as it is; reparam
  // re-lays the three marker images. Scored that way both q measured 'UV.png' alone (0 and
  // 0). The views now draw a re-laid marker's primitives, so both q are measured, and the
  // other two markers are named as unseen.
  if (!test::shared_dir()) UVPRESS_SKIP("../shared is absent");
  auto engine = engine::make_cpu_engine({});
  pipeline::ReparamOptions o;
  o.cost = 0.5, o.score_resolution = 512, o.triangle.evaluations = 12;
  io::GltfFile out = io::load_gltf((*test::shared_dir() / "assets/TextureTransformTest/glTF/TextureTransformTest.gltf").string());
  const pipeline::ReparamResult r = pipeline::reparam(out, *engine, o);
  REQUIRE(r.guard.ran);
  CHECK(r.guard.q_reparam > 0);  // a changed layout, measured
  CHECK(r.guard.q_resize > 0);
  CHECK(r.guard.unseen.size() == 2);  // two of Correct.png, NotSupported.png, Error.png
  const auto report = r.to_json();
  CHECK(report["guard"]["unseen"].size() == 2);
  bool said = false;
  for (const auto& w : report["warnings"]) said |= w.get<std::string>().rfind("scoring: the views draw the primitives of image", 0) == 0;
  CHECK(said);
  // MultiUVTest: the views draw its base colour's layout (TEXCOORD_0); its emissive map on
  // TEXCOORD_1 is re-laid too, and q cannot see it: the report names it.
  io::GltfFile multi = io::load_gltf((*test::shared_dir() / "assets/MultiUVTest/glTF/MultiUVTest.gltf").string());
  pipeline::ReparamOptions paper = o;
  paper.candidates = false;  // the paper's layout alone: the guard is what is checked
  const pipeline::ReparamResult m = pipeline::reparam(multi, *engine, paper);
  REQUIRE(m.guard.ran);
  CHECK(m.guard.unseen == std::vector<std::string>{"uv1.png"});
  // One re-baked texture, drawn: nothing unseen (the demo).
  io::GltfFile demo = pipeline::make_demo_asset({16, 128});
  o.triangle.view_size = 16;
  const pipeline::ReparamResult d = pipeline::reparam(demo, *engine, o);
  REQUIRE(d.guard.ran);
  CHECK(d.guard.unseen.empty());
  CHECK(d.to_json()["guard"].count("unseen") == 0);
}

TEST_CASE("reparam --max-gmsd: the cheapest size that meets the bound, tighter bounds cost more", "[pipeline][reparam]") {
  auto engine = engine::make_cpu_engine({});
  const io::GltfFile in = pipeline::make_demo_asset({16, 256});
  auto run = [&](double bound) {
    io::GltfFile out = in;
    pipeline::ReparamOptions o;
    o.max_gmsd = bound;
    o.triangle.evaluations = 12;
    o.triangle.view_size = 16;
    const pipeline::ReparamResult result = pipeline::reparam(out, *engine, o);
    auto report = result.to_json();
    INFO(report["max_gmsd"].dump());
    CHECK(report["flips"] == 0);
    if (report["max_gmsd"]["met"].get<bool>()) CHECK(report["max_gmsd"]["q"].get<double>() <= bound);
    REQUIRE(result.textures.size() == 1);
    return result.textures[0].new_size[0];
  };
  const uint32_t loose = run(0.06), tight = run(0.02);
  CHECK(loose < tight);
  CHECK(loose < 256);
}

TEST_CASE("reparam's guard writes the plain resize when the layout loses, and reparam's layout with --force-reparam",
          "[pipeline][reparam][shared]") {
  if (!test::shared_dir()) UVPRESS_SKIP("../shared is absent");
  auto engine = engine::make_cpu_engine({});
  // Duck's charts only repacked at half the texels with a 1-texel gutter into an atlas of
  // the source's (square) shape: its atlas is already tight, so the repack gets a smaller
  // scale than a resize, is resampled twice, and its charts bleed into each other from the
  // first mip level on: built to lose (q 0.00096 against the resize's 0.00069). At a
  // 4-texel gutter it lost while its sides were free (0.00027 against 0.00023); with sides
  // multiples of 4 (session 57) its mip chain is exact boxes and it wins, 0.00066 against
  // 0.00077. Duck as a truecolour input: written in its own palette, the resize's blends
  // lose more to it than the repack's aligned copies do, and the repack wins (0.00081
  // against 0.00090).
  const io::GltfFile in = truecolour(shared_duck());
  io::GltfFile out = in, layout;
  pipeline::ReparamOptions losing = keep_shapes(0.5);
  losing.gutter = 1;
  losing.keep_aspect = true;
  auto report = pipeline::reparam(out, *engine, losing, {}, &layout).to_json();
  INFO(report.dump());
  REQUIRE(report["guard"].is_object());
  const double q_reparam = report["guard"]["q_reparam"].get<double>(), q_resize = report["guard"]["q_resize"].get<double>();
  CHECK(q_resize < q_reparam);
  CHECK(report["chosen"] == "resize");
  // What was written is the resize: the input's UVs, and it scores (independently, as
  // written) what the guard measured; reparam's layout scores its own q.
  const io::Asset a = io::build_asset(in), b = io::build_asset(out);
  REQUIRE(a.primitives.size() == b.primitives.size());
  CHECK(a.primitives[0].uv_sets[0].uv == b.primitives[0].uv_sets[0].uv);
  eval::EvalOptions eo;
  eo.artifacts = false;
  auto written = eval::score_as_written(in, out, *engine, eo);
  CHECK(written.q == Approx(q_resize).epsilon(1e-9));
  CHECK(written.c_r == Approx(report["cost_ratio"].get<double>()).epsilon(1e-9));
  CHECK(eval::score_as_written(in, layout, *engine, eo).q == Approx(q_reparam).epsilon(1e-9));
  // The same two files from afar (views of 256 pixels), as the report says.
  REQUIRE(report["guard"]["far"].is_object());
  eval::EvalOptions far = eo;
  far.resolution = 256;
  CHECK(report["guard"]["far"]["resolution"] == 256);
  CHECK(eval::score_as_written(in, out, *engine, far).q == Approx(report["guard"]["far"]["q_resize"].get<double>()).epsilon(1e-9));
  CHECK(eval::score_as_written(in, layout, *engine, far).q == Approx(report["guard"]["far"]["q_reparam"].get<double>()).epsilon(1e-9));
  // --force-reparam: reparam's layout is written, with the score the guard reported.
  pipeline::ReparamOptions forced = losing;
  forced.guard = false;
  io::GltfFile out2 = in;
  auto report2 = pipeline::reparam(out2, *engine, forced).to_json();
  CHECK(report2["chosen"] == "reparam");
  CHECK(eval::score_as_written(in, out2, *engine, eo).q == Approx(q_reparam).epsilon(1e-9));
}

TEST_CASE("reparam --no-optimize at cost 1: charts that fit at scale 1 keep their texels exactly (lossless)",
          "[pipeline][reparam]") {
  auto engine = engine::make_cpu_engine({});
  // The demo sheet with its chart shrunk into 60 % of the texture at a sub-texel offset:
  // it fits at the source density, so a repack moves it by whole texels and copies them.
  io::GltfFile in = pipeline::make_demo_asset({16, 256});
  {
    const io::Asset a = io::build_asset(in);
    std::vector<float> uv = a.primitives[0].uv_sets[0].uv;
    for (size_t k = 0; k < uv.size(); k += 2)
      uv[k] = 0.1f + 0.6f * uv[k] + 0.37f / 256, uv[k + 1] = 0.2f + 0.6f * uv[k + 1] + 0.21f / 256;
    auto& prim = in.model.meshes[size_t(a.primitives[0].mesh)].primitives[size_t(a.primitives[0].primitive)];
    prim.attributes["TEXCOORD_0"] = io::append_float_accessor(in.model, uv, TINYGLTF_TYPE_VEC2);
  }
  eval::EvalOptions eo;
  eo.artifacts = false;
  // Level 0 only: its texels are the claim. A mip chain of the smaller atlas, the chart
  // moved, averages other 2 x 2 blocks than the input's does (q 0.004 trilinear).
  eo.filter = eval::TextureFilter::Bilinear;
  pipeline::ReparamOptions o = keep_shapes(1.0);
  o.guard = false;  // at cost 1 the "resize" is the input itself: a tie the guard would give to it
  io::GltfFile out = in;
  const pipeline::ReparamResult result = pipeline::reparam(out, *engine, o);
  INFO(result.to_json().dump());
  REQUIRE(result.layouts.size() == 1);
  const pipeline::LayoutReport& layout = result.layouts[0];
  CHECK(layout.scale == Approx(1.0).margin(1e-12));
  CHECK(layout.exact_units == 1);
  const io::Asset a = io::build_asset(in), b = io::build_asset(out);
  CHECK(a.primitives[0].uv_sets[0].uv != b.primitives[0].uv_sets[0].uv);  // moved
  const double q = eval::score_as_written(in, out, *engine, eo).q;
  CHECK(q < 1e-6);
  // The same repack resampled (texels not copied) is measurably lossy: what the copy saves.
  o.exact_texels = false;
  io::GltfFile resampled = in;
  pipeline::reparam(resampled, *engine, o);
  CHECK(eval::score_as_written(in, resampled, *engine, eo).q > 1e-4);
}

TEST_CASE("reparam's gutter at the image edges follows the sampler: none where it clamps, half where it repeats",
          "[pipeline][reparam]") {
  auto engine = engine::make_cpu_engine({});
  // The demo sheet: one chart over the whole texture, its sampler clamping. Repacked at
  // half the texels it is resampled (no texel copies), so nothing needs room at the edges:
  // the chart fills the image (with the gutter at the edges it covered 91 %: q 0.0240
  // instead of 0.0221 on the full-size demo).
  const io::GltfFile clamped = pipeline::make_demo_asset({16, 256});
  pipeline::ReparamOptions o = keep_shapes(0.5);
  o.guard = false;
  o.score_resolution = 512;
  io::GltfFile out = clamped;
  pipeline::ReparamResult r = pipeline::reparam(out, *engine, o);
  INFO(r.to_json().dump());
  REQUIRE(r.layouts.size() == 1);
  const uint32_t g = r.layouts[0].gutter;
  CHECK(g >= 4);
  CHECK(r.layouts[0].edge_gutter == std::array<uint32_t, 2>{0, 0});
  CHECK(r.layouts[0].packing_efficiency > 0.99);
  // At cost 1 it fits at scale 1, so its texels are copied: nothing is lost (with the
  // gutter at the edges it got scale 0.94).
  o.cost = 1.0;
  out = clamped;
  r = pipeline::reparam(out, *engine, o);
  REQUIRE(r.layouts.size() == 1);
  CHECK(r.layouts[0].scale == Approx(1.0).margin(1e-12));
  CHECK(r.layouts[0].exact_units == 1);
  eval::EvalOptions eo;
  eo.artifacts = false;
  eo.filter = eval::TextureFilter::Bilinear;
  CHECK(eval::score_as_written(clamped, out, *engine, eo).q < 1e-6);
  // The same asset at half the texels with a sampler that repeats along u only.
  o.cost = 0.5;
  io::GltfFile wrapped = clamped;
  wrapped.model.samplers[0].wrapS = TINYGLTF_TEXTURE_WRAP_REPEAT;
  out = wrapped;
  r = pipeline::reparam(out, *engine, o);
  REQUIRE(r.layouts.size() == 1);
  // Half the gutter of the layout kept (the wide-gutter variant may win here).
  const uint32_t gw = r.layouts[0].gutter;
  CHECK(r.layouts[0].edge_gutter == std::array<uint32_t, 2>{(gw + 1) / 2, 0});
  CHECK(r.layouts[0].packing_efficiency < 0.99);
}

TEST_CASE("reparam prunes what it replaced: no new UNUSED_OBJECT or error, and a reparam of its output does not grow",
          "[pipeline][reparam][shared][prune]") {
  if (!test::shared_dir()) UVPRESS_SKIP("../shared is absent");
  auto engine = engine::make_cpu_engine({});
  test::Scratch dir("reparam-prune");
  const auto input = *test::shared_dir() / "assets" / "Duck" / "glTF-Binary" / "Duck.glb";
  // reparam's layout written (not the guard's resize), so that UVs are replaced too.
  pipeline::ReparamOptions o = keep_shapes(0.5);
  o.guard = false;
  auto run = [&](const fs::path& from, const fs::path& to) {
    io::GltfFile f = io::load_gltf(from.string());
    auto report = pipeline::reparam(f, *engine, o).to_json();
    CHECK(report["chosen"] == "reparam");
    io::save_gltf(f, to.string());
    return f;
  };
  // The bytes that are not images: JSON, geometry, UVs (and any leftovers).
  auto non_image = [](const fs::path& glb, const io::GltfFile& f) {
    uint64_t images = 0;
    for (const auto& b : f.image_bytes) images += b.size();
    return int64_t(fs::file_size(glb)) - int64_t(images);
  };
  const io::GltfFile first = run(input, dir / "once.glb");
  const io::GltfFile second = run(dir / "once.glb", dir / "twice.glb");
  const auto v_in = test::validate_gltf(input), v_once = test::validate_gltf(dir / "once.glb"),
             v_twice = test::validate_gltf(dir / "twice.glb");
  for (const auto* v : {&v_once, &v_twice}) {
    INFO((*v).dump());
    CHECK((*v)["numErrors"].get<int>() <= v_in["numErrors"].get<int>());
    for (auto& [code, count] : (*v)["errors"].items()) CHECK(count.get<int>() <= v_in["errors"].value(code, 0));
    CHECK((*v)["codes"].value("UNUSED_OBJECT", 0) <= v_in["codes"].value("UNUSED_OBJECT", 0));
  }
  // Geometry and UVs weigh the same after one reparam and after two (16-byte alignment of
  // the image chunks aside); only the image bytes may change. The old file grew by every
  // replaced image and UV set (Duck: 117.7 KB -> 151.7 KB at cost 0.5).
  const int64_t once = non_image(dir / "once.glb", first), twice = non_image(dir / "twice.glb", second);
  INFO("non-image bytes: once " << once << ", twice " << twice);
  CHECK(std::abs(once - twice) <= 32);
  CHECK(fs::file_size(dir / "twice.glb") <= fs::file_size(dir / "once.glb"));
  // The input's own non-image bytes plus at most the UVs as floats (Duck's are floats).
  io::GltfFile in = io::load_gltf(input.string());
  CHECK(once <= non_image(input, in) + 64);
}

TEST_CASE("reparam on the demo asset at half the texels beats the plain resize by more than eval's noise floor",
          "[pipeline][reparam][demo-quality]") {
  // Issue 17's demo case, at the README demo's budget (40 evaluations a triangle; `bench
  // quality` measures the full 100) and eval's default views: reparam keeps its own layout,
  // and the file it writes scores, independently and as written, below the resize it was
  // compared with by more than the noise floor eval measures for this asset.
  auto engine = engine::make_cpu_engine({});
  const io::GltfFile in = pipeline::make_demo_asset();
  io::GltfFile out = in;
  pipeline::ReparamOptions o;
  o.cost = 0.5;
  o.triangle.evaluations = 40;
  const auto report = pipeline::reparam(out, *engine, o).to_json();
  INFO(report["candidates"].dump());
  REQUIRE(report["guard"].is_object());
  CHECK(report["chosen"] == "reparam");
  eval::EvalOptions eo;
  eo.artifacts = false;
  eo.cost_grid = {0.5};
  const auto ev = eval::evaluate(in, {{"reparam", &out}}, *engine, eo);
  const double floor = ev.noise_floor();
  const double q_written = eval::score_as_written(in, out, *engine, eo).q;
  const double q_resize = report["guard"]["q_resize"].get<double>();
  INFO("q written " << q_written << ", resize " << q_resize << ", noise floor " << floor);
  CHECK(floor > 0);
  CHECK(q_written == Approx(report["guard"]["q_reparam"].get<double>()).epsilon(1e-9));
  CHECK(q_written < q_resize - floor);
  // The kept plan reshapes the demo's one chart: its least-squares variant is built once,
  // not again as `-resampled` (with no texels to copy, the same build).
  const std::string kept = report["layout"].get<std::string>();
  const std::string base = kept.substr(0, kept.find('+'));
  CHECK(report["layouts"][0]["exact_units"] == 0);
  CHECK(candidate_score(report, base + "+least-squares").first > 0);
  CHECK(candidate_score(report, base + "+least-squares-resampled").first == -1.0);
  // Each candidate's own seconds: its parts of the stages' totals, which they add up to.
  double built = 0, scored = 0;
  for (const auto& c : report["candidates"]) {
    const auto& t = c["seconds"];
    for (const char* k : {"mesh_stage", "pack", "rebake", "score"}) CHECK(t[k].get<double>() >= 0);
    built += t["mesh_stage"].get<double>() + t["pack"].get<double>() + t["rebake"].get<double>();
    scored += t["score"].get<double>();
  }
  CHECK(built > 0);
  CHECK(built <= report["stages"]["candidates_built"].get<double>());
  CHECK(scored > 0);
  CHECK(scored <= report["stages"]["candidates_and_guard"].get<double>());
}

TEST_CASE("reparam on Duck at half the texels: gutters and mip alignment built, the best written, beating the resize",
          "[pipeline][reparam][shared][wide-gutter][mip-aligned]") {
  // Issue 17's Duck case. Duck's charts share texels and can only be repacked (or scaled
  // as whole units, the unit-scale candidate); where views sample coarse mip levels the
  // repacked charts bleed into each other, while the input's charts sit in the yellow they
  // continue into on the mesh, so the kept plan and the best other are also built with
  // gutters a mip level cleaner (16 texels instead of 8 at 362^2). Which wins is a matter of
  // where the packer puts the eye next to the body: the repack in a square atlas at costs
  // 0.48, 0.50, 0.52, 0.54 scored q 0.000785, 0.000779, 0.00075, 0.00061 at 8 texels and
  // 0.000969, 0.000675, 0.000739, 0.000742 at 16, and the resize's 0.000692 is inside that
  // spread (eval's noise floor for Duck is 1.4e-4). So this checks what must hold whatever
  // the arrangement: both gutters were built and scored, and the file written scores the
  // best of every candidate and the resize, as the guard said.
  if (!test::shared_dir()) UVPRESS_SKIP("../shared is absent");
  auto engine = engine::make_cpu_engine({});
  pipeline::ReparamOptions o;
  o.cost = 0.5;
  const DuckRun run = reparam_duck(*engine, o);
  const pipeline::ReparamResult& result = run.result;
  const auto& report = run.report;
  INFO(report["candidates"].dump());
  REQUIRE(report["guard"].is_object());
  const double q_default = candidate_score(report, "repack").first;
  const double q_wide = candidate_score(report, "repack+wide-gutter").first;
  CHECK(q_default > 0);
  CHECK(q_wide > 0);
  CHECK(q_wide != q_default);
  double q_best = 1;
  std::string best;
  for (const auto& c : report["candidates"])
    if (c["q"].get<double>() >= 0 && c["q"].get<double>() < q_best) q_best = c["q"].get<double>(), best = c["name"];
  const double q_resize = report["guard"]["q_resize"].get<double>();
  REQUIRE(result.layouts.size() == 1);
  CHECK(result.layouts[0].gutter == (best.find("+wide-gutter") != std::string::npos ? 16u : 8u));
  CHECK(report["layout"] == best);
  CHECK(report["chosen"] == (q_best < q_resize ? "reparam" : "resize"));
  eval::EvalOptions eo;
  eo.artifacts = false;
  const double q_written = eval::score_as_written(run.in, run.out, *engine, eo).q;
  CHECK(q_written == Approx(std::min(q_best, q_resize)).epsilon(1e-9));
  // Duck's plans keep every chart's shape and copy its texels, so the best plan's
  // least-squares variant is also built with them resampled (which differs).
  std::string lsq;
  for (const auto& c : report["candidates"]) {
    const std::string name = c["name"];
    if (name.size() > 14 && name.substr(name.size() - 14) == "+least-squares") lsq = name;
  }
  REQUIRE(!lsq.empty());
  const double q_copied = candidate_score(report, lsq).first, q_resampled = candidate_score(report, lsq + "-resampled").first;
  CHECK(q_resampled > 0);
  CHECK(q_resampled != q_copied);
  // The kept plan copies units, so it is also built with the mip chain kept whole (both
  // depths) at both gutters, and the best other plan too; the kept plan's four pin its
  // copies at the source's density, so each is built with one scale for all as well
  // (`-one-scale`), and pinned scores better (measured at 8 texels: 0.000292 against
  // 0.000686 at A, 0.000346 against 0.000401 at 2A; at 16: 0.000187 against 0.000618,
  // 0.000170 against 0.000618).
  CHECK(best_aligned(report).second == 9);
  for (const char* gutter : {"", "+wide-gutter"})
    for (const char* depth : {"+mip-aligned", "+mip-aligned-deep"}) {
      const std::string pinned = lsq + gutter + depth;
      INFO(pinned);
      const double q_pinned = candidate_score(report, pinned).first, q_one = candidate_score(report, pinned + "-one-scale").first;
      CHECK(q_pinned > 0);
      CHECK(q_one > 0);
      CHECK(q_pinned < q_one);
    }
  CHECK(best.find("+mip-aligned") != std::string::npos);
  CHECK(best.find("-one-scale") == std::string::npos);
  if (best.find("+mip-aligned") != std::string::npos) {
    const pipeline::LayoutReport& l = result.layouts[0];
    CHECK(l.mip_align == l.gutter);  // 8 or 16: powers of two
    CHECK(l.side_multiple == (best.find("-deep") != std::string::npos ? 2 : 1) * l.mip_align);
    CHECK(l.atlas[0] % l.side_multiple == 0);
    CHECK(l.atlas[1] % l.side_multiple == 0);
    // The aligned variants keep their copies at the source's density (Candidate::
    // pin_copies) where they fit so, as Duck's do at half its texels.
    CHECK(l.pinned_units == l.exact_units);
    CHECK(l.pinned_units > 0);
  }
  // Issue 17: at half the texels Duck writes reparam's layout, and it beats the input
  // resized to half its texels at its own aspect (eval's baseline) by more than eval's
  // noise floor. Measured: 0.00037 against 0.00069, floor 0.00014 (before the mip-aligned
  // variants the resize was written: 0.00074 against 0.00069); 0.00028 since the aligned
  // variants pin their copies at the source's density, and then by more than half (0.00029
  // written in Duck's own palette, below); 0.00017 since the kept plan is aligned at the
  // wide gutter too (16 texels, sides multiples of 32), against 0.00069.
  CHECK(report["chosen"] == "reparam");
  // The guard's resize is the better of two sizes at most the layout's texels: the nearest
  // (here 359 x 359, an odd side, whose mip chain drifts) and sides multiples of the layout's
  // 32 (352 x 352). The second wins: each written as a truecolour PNG and scored as written,
  // q 0.00089 at 359, 0.00068 at 352.
  {
    const pipeline::LayoutReport& l = result.layouts[0];
    const double texels = double(l.atlas[0]) * l.atlas[1];
    const uint32_t nearest = uint32_t(std::lround(std::sqrt(texels))), aligned = uint32_t(std::sqrt(texels)) / l.side_multiple * l.side_multiple;
    const Image source = io::decode_image(run.in.image_bytes[0], "DuckCM.png");
    auto resized_q = [&](uint32_t side) {
      io::GltfFile f = run.in;
      f.image_bytes[0] = io::encode_image(eval::resize_lanczos3(source, side, side, false), "png");
      return eval::score_as_written(run.in, f, *engine, eo).q;
    };
    const double q_nearest = resized_q(nearest), q_aligned = resized_q(aligned);
    INFO("resize at " << nearest << ": " << q_nearest << ", at " << aligned << ": " << q_aligned);
    CHECK(nearest % 2 == 1);
    CHECK(aligned < nearest);
    CHECK(q_aligned < q_nearest);
    CHECK(report["guard"]["resize_sides"] == "aligned");
  }
  const eval::EvalResult half = input_at(run.in, *engine, 0.5);
  REQUIRE(half.layouts.size() == 1);
  REQUIRE(half.layouts[0].curve.size() == 1);
  const double q_half = half.layouts[0].curve[0].q, floor = half.noise_floor();
  INFO("written " << q_written << ", resize at half " << q_half << ", noise floor " << floor);
  CHECK(floor > 0);
  CHECK(q_written < q_half - floor);
  CHECK(q_written < 0.5 * q_half);
  // Issue 18: the texture is written in Duck's own palette (every texel one of the input's
  // 54 colours) and costs at most 0.6 of the input's bytes and 1.1 of the resize's to the
  // same texels encoded alike. Measured: 8,940 bytes, 0.55 and 0.85 (a new 256-colour
  // palette, dithered, and zlib: 12,349 bytes, 0.76); 9,397 bytes, 0.58 and 0.84 at the
  // wide gutter's aligned layout (288 x 448).
  const auto& tex = report["textures"][0];
  INFO(tex.dump());
  CHECK(tex["bytes_ratio"].get<double>() <= 0.6);
  CHECK(tex["bytes_vs_resize"].get<double>() <= 1.1);
  CHECK(tex["written"] == "png (8-bit palette)");
  auto colours = [](const Image& img) {
    std::set<std::array<long, 3>> c;
    for (uint32_t y = 0; y < img.height; ++y)
      for (uint32_t x = 0; x < img.width; ++x)
        c.insert({std::lround(img.at(x, y, 0) * 255), std::lround(img.at(x, y, 1) * 255), std::lround(img.at(x, y, 2) * 255)});
    return c;
  };
  const auto in_colours = colours(io::decode_image(run.in.image_bytes[0], "in"));
  const auto out_colours = colours(io::decode_image(run.out.image_bytes[0], "out"));
  CHECK(in_colours.size() == 54);
  CHECK(std::includes(in_colours.begin(), in_colours.end(), out_colours.begin(), out_colours.end()));
}

TEST_CASE("reparam --no-optimize at cost 1 on Duck: with the mip chain kept whole, copies look the same in mip-mapped views",
          "[pipeline][reparam][shared][mip-aligned]") {
  // Duck's own charts fit at the source density, so a repack copies their texels: level 0
  // is the input's (q ~ 1e-9 in bilinear views). In trilinear views the repack still
  // scored q 0.00070 (0.00068 at the wide gutter), as much as the resize to half the
  // texels: the copies sat at odd offsets in a 514 x 432 image, whose coarser levels
  // average other blocks than the input's 512 x 512 chain does. Aligned (sides multiples of
  // 32, copies moved by multiples of 16): q 2.1e-5. Since then the texture is written in
  // Duck's own palette, whose loss is most of what is left (aligned: 0.00021), and every
  // candidate's sides are multiples of the gutter's 8 (session 57), so the plain repack
  // differs from the aligned one by its copies' offsets alone: 0.00056 against 0.00021.
  if (!test::shared_dir()) UVPRESS_SKIP("../shared is absent");
  auto engine = engine::make_cpu_engine({});
  pipeline::ReparamOptions o = keep_shapes(1.0);
  o.guard = false;  // at cost 1 the resize is the input itself
  const DuckRun run = reparam_duck(*engine, o);
  const auto& report = run.report;
  INFO(report["candidates"].dump());
  const double q_repack = candidate_score(report, "repack").first;
  REQUIRE(q_repack > 0);
  const auto [q_aligned, aligned] = best_aligned(report);
  REQUIRE(aligned > 0);
  CHECK(q_aligned < 0.5 * q_repack);
  CHECK(report["layout"].get<std::string>().find("+mip-aligned") != std::string::npos);
  REQUIRE(run.result.layouts.size() == 1);
  CHECK(run.result.layouts[0].exact_units == run.result.layouts[0].packing_units);
}

TEST_CASE("reparam on Duck: units that share texels trade density as wholes and beat the plain repack",
          "[pipeline][reparam][shared][unit-scale]") {
  // Duck's charts all share texels with their mirrored halves, so none can be reshaped;
  // the unit-scale candidate still moves texels from its smooth units to the eye's, each
  // unit at one uniform scale (the equal-slope allocation over whole units). At a quarter
  // of the texels it scores below the plain repack by more than eval's noise floor, keeps
  // the mirrored halves on shared texels, and spends the budget (the allocation's share is
  // raised until the units fill it).
  if (!test::shared_dir()) UVPRESS_SKIP("../shared is absent");
  auto engine = engine::make_cpu_engine({});
  pipeline::ReparamOptions o;
  o.cost = 0.25;
  o.guard = false;
  const DuckRun run = reparam_duck(*engine, o);
  const pipeline::ReparamResult& result = run.result;
  const auto& report = run.report;
  INFO(report["candidates"].dump());
  const double q_repack = candidate_score(report, "repack").first;
  const auto [q_units, cost_units] = candidate_score(report, "unit-scale");
  REQUIRE(q_repack > 0);
  REQUIRE(q_units > 0);
  const double floor = input_at(run.in, *engine, 0.25).noise_floor();
  INFO("q unit-scale " << q_units << ", repack " << q_repack << ", noise floor " << floor);
  CHECK(floor > 0);
  CHECK(q_units < q_repack - floor);
  CHECK(cost_units > 0.24);
  CHECK(cost_units <= 0.25 + 1e-9);
  CHECK(report["overlaps_new"] == 0);
  // The report describes the kept layout's units: unit-scale (or a variant of it) is kept.
  REQUIRE(report["layout"].get<std::string>().rfind("unit-scale", 0) == 0);
  REQUIRE(result.layouts.size() == 1);
  const pipeline::LayoutReport& layout = result.layouts[0];
  CHECK(layout.shared_texel_charts == 8);
  REQUIRE(layout.unit_scale);
  const pipeline::UnitScaleReport& u = *layout.unit_scale;
  CHECK(u.scale_min < 0.5);  // smooth units gave texels up ...
  CHECK(u.scale_quartiles[2] > 0.8);  // ... to the detailed ones, the largest at 1
  CHECK(u.scale_quartiles[2] <= 1.0);
  CHECK(u.cost >= 0.25);
}

TEST_CASE("reparam's own curve chooses plan and gutter at each cost: Duck at a tenth of the texels beats the resize",
          "[pipeline][reparam][shared][curve]") {
  // Issue 17: bench quality's ratios come from reparam's own q-c curve. The plan kept at half
  // of Duck's texels (repack, wide gutter) is not the best at a tenth: built there it scored
  // q 0.00179 against the resize's 0.00155, and Duck's ratio went above 1. At each cost the
  // curve takes the best of the plans reparam chose among (the kept one and the best other
  // base plan, each at both gutters, and the second-best other), so at a tenth it beats the resize by more than eval's
  // noise floor, and it is never worse at the requested cost than the kept layout itself.
  if (!test::shared_dir()) UVPRESS_SKIP("../shared is absent");
  auto engine = engine::make_cpu_engine({});
  pipeline::ReparamOptions o;
  o.cost = 0.5;
  o.curve_costs = {0.1, 0.5};
  const DuckRun run = reparam_duck(*engine, o);
  const pipeline::ReparamResult& result = run.result;
  INFO(run.report["candidates"].dump() << "\n" << run.report["curve"].dump());
  REQUIRE(result.curve);
  REQUIRE(result.curve->size() == 2);
  const auto& tenth = (*result.curve)[0];
  const auto& half = (*result.curve)[1];
  // Within 1.2 % of the costs: a +mip-aligned layout's sides are rounded down to multiples
  // of 8 or 16 (Duck's at half the texels: 368 x 352, c_r 0.494).
  CHECK(tenth.c_r == Approx(0.1).margin(0.005));
  CHECK(half.c_r == Approx(0.5).margin(0.008));
  // The requested cost's point is at least as good as what reparam kept there.
  REQUIRE(result.guard.ran);
  CHECK(half.q <= result.guard.q_reparam + 1e-12);
  const eval::EvalResult resize = input_at(run.in, *engine, 0.1);
  const double floor = resize.noise_floor(), q_resize = resize.layouts[0].curve[0].q;
  INFO("curve at 0.1: q " << tenth.q << " (" << tenth.layout << "), resize " << q_resize << ", noise floor " << floor);
  CHECK(floor > 0);
  CHECK(tenth.q < q_resize - floor);
}

TEST_CASE("reparam on Duck at a tenth of the texels: the allocation made for half the texels, scaled down, wins",
          "[pipeline][reparam][shared][unit-scale]") {
  // Below half the texels the allocating plans are also built with their allocation made
  // for half the texels and scaled into the budget (choose_layout). On Duck at a tenth the
  // unit-scale allocation made there gives the eye's units the source density and starves
  // the rest (q 0.00134); the half's allocation scaled down scores 0.00107, and the written
  // file beats the resize (0.00156) by more than eval's noise floor. Duck as a truecolour
  // input: written in its own palette the two score 0.00125 and 0.00123 (noise floor
  // 0.00014), the palette's loss then as large as the allocation's gain.
  if (!test::shared_dir()) UVPRESS_SKIP("../shared is absent");
  auto engine = engine::make_cpu_engine({});
  pipeline::ReparamOptions o;
  o.cost = 0.1;
  const DuckRun run = reparam_duck(*engine, o, true);
  const pipeline::ReparamResult& result = run.result;
  const auto& report = run.report;
  INFO(report["candidates"].dump());
  const double q_here = candidate_score(report, "unit-scale").first;
  const auto [q_half, cost_half] = candidate_score(report, "unit-scale+half-allocation");
  REQUIRE(q_here > 0);
  REQUIRE(q_half > 0);
  CHECK(cost_half == Approx(0.1).margin(0.002));
  const double floor = input_at(run.in, *engine, 0.1).noise_floor();
  INFO("q unit-scale " << q_here << ", with the half's allocation " << q_half << ", noise floor " << floor);
  CHECK(floor > 0);
  CHECK(q_half < q_here - floor);
  CHECK(report["chosen"] == "reparam");
  CHECK(report["layout"].get<std::string>().rfind("unit-scale+half-allocation", 0) == 0);
  REQUIRE(result.guard.ran);
  CHECK(result.guard.q_reparam < result.guard.q_resize - floor);
  REQUIRE(result.layouts.size() == 1);
  REQUIRE(result.layouts[0].unit_scale);
  CHECK(result.layouts[0].unit_scale->cost == Approx(0.5));  // the allocation's share
}

TEST_CASE("reparam on CesiumMilkTruck: its layout re-baked at c_r 1 looks better than the input resized to c_r 0.5",
          "[pipeline][reparam][shared][truck]") {
  // Issue 17's broken case: the truck (two meshes, one shared atlas, rigid charts) once came
  // out 10x worse than its resize at every cost. reparam at half the texels, the paper's
  // layout alone (the triangle stage's targets through the mesh stage: the reshaping that
  // was broken; the candidates would cost two more minutes here), then eval: that layout
  // re-baked from the full texture at the input's texels (eval's curve of the layout at
  // c_r 1) must beat the input resized to half its texels. Measured: q 0.0149 against
  // 0.0158 (eval's default views, rolled and cropped at the 2560-px cap; eval re-bakes the
  // full texture into a layout with the area filter); the layout reparam keeps by default,
  // 0.0138-0.0141.
  if (!test::shared_dir()) UVPRESS_SKIP("../shared is absent");
  auto engine = engine::make_cpu_engine({});
  const io::GltfFile in =
      io::load_gltf((*test::shared_dir() / "assets" / "CesiumMilkTruck" / "glTF" / "CesiumMilkTruck.gltf").string());
  io::GltfFile out = in;
  pipeline::ReparamOptions o;
  o.cost = 0.5;
  o.candidates = false;
  o.guard = false;
  const pipeline::ReparamResult result = pipeline::reparam(out, *engine, o);
  REQUIRE(result.chosen == "reparam");
  REQUIRE(result.triangles_optimized > 0);
  eval::EvalOptions eo;
  eo.artifacts = false;
  eo.noise_floor = false;  // compared by a wide margin, not within the noise
  eo.cost_grid = {0.5, 1.0};
  const eval::EvalResult r = eval::evaluate(in, {{"reparam", &out}}, *engine, eo);
  REQUIRE(r.layouts.size() == 2);
  REQUIRE(r.layouts[0].curve.size() == 2);
  REQUIRE(r.layouts[1].curve.size() == 2);
  const double q_resize_half = r.layouts[0].curve[0].q, q_layout_full = r.layouts[1].curve[1].q;
  INFO("reparam layout at c_r 1: q " << q_layout_full << ", input resized to c_r 0.5: q " << q_resize_half);
  CHECK(r.layouts[1].curve[1].c_r == Approx(1.0));
  CHECK(q_layout_full < q_resize_half);
}
