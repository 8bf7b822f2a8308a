// eval: whole-mesh renders on both backends, q-c curves, savings. `uvpress eval` and its
// HTML report: tests/cli/test_eval.cpp.
#include <catch2/catch.hpp>

#include "core/error.h"
#include "engine.h"
#include "eval/eval.h"
#include "eval/resize.h"
#include "io/asset.h"
#include "io/image_io.h"
#include "perceptual/triangle_view.h"
#include "pipeline/demo_asset.h"
#include "support.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <cmath>
#include <functional>

using namespace uvpress;

namespace {

struct DemoMesh {
  io::GltfFile file;
  io::Asset asset;
  Image texture;
};

DemoMesh demo(int grid = 16, int texture = 128) {
  DemoMesh d;
  pipeline::DemoOptions o;
  o.grid = grid, o.texture_size = texture;
  d.file = pipeline::make_demo_asset(o);
  d.asset = io::build_asset(d.file);
  d.texture = io::decode_image(d.file.image_bytes[0], "demo");
  return d;
}

engine::MeshRenderDesc render_desc(const DemoMesh& d, const std::vector<float>& texture, uint32_t channels,
                                   uint32_t size, bool repeat) {
  const auto& p = d.asset.primitives.at(0);
  engine::MeshRenderDesc r;
  r.width = size, r.height = size + 8;  // not square, not a multiple of the tile
  r.cameras = eval::dodecahedron_cameras(p.positions.data(), p.vertex_count());
  r.positions = p.positions.data(), r.vertex_count = p.vertex_count();
  r.indices = p.indices.data(), r.triangle_count = p.triangle_count();
  r.uvs = p.uv_sets[0].uv.data();
  r.texture = texture.data(), r.texture_width = d.texture.width, r.texture_height = d.texture.height;
  r.channels = channels, r.repeat = repeat;
  return r;
}

// Small views (64 px) at a quarter of the texels and at all of them, no artifacts: what
// the tests on the small demo need.
eval::EvalOptions two_costs() {
  eval::EvalOptions o;
  o.resolution = 64;
  o.cost_grid = {0.25, 1.0};
  o.artifacts = false;
  return o;
}

}  // namespace

TEST_CASE("dodecahedron cameras frame the whole mesh from 20 directions", "[eval]") {
  DemoMesh d = demo();
  const auto& p = d.asset.primitives[0];
  auto cams = eval::dodecahedron_cameras(p.positions.data(), p.vertex_count());
  REQUIRE(cams.size() == 20);
  for (const auto& m : cams)
    for (size_t v = 0; v < p.vertex_count(); ++v) {
      double c[4];
      for (int r = 0; r < 4; ++r)
        c[r] = m[size_t(4 * r)] * p.positions[3 * v] + m[size_t(4 * r + 1)] * p.positions[3 * v + 1] +
               m[size_t(4 * r + 2)] * p.positions[3 * v + 2] + m[size_t(4 * r + 3)];
      REQUIRE(c[3] > 0);
      REQUIRE(std::abs(c[0] / c[3]) < 1.0);
      REQUIRE(std::abs(c[1] / c[3]) < 1.0);
    }
}

TEST_CASE("render_mesh: Vulkan (lavapipe, validation on) matches the CPU oracle", "[eval][engine]") {
  UVPRESS_LAVAPIPE_OR_SKIP(vk);
  auto cpu = engine::make_cpu_engine({});
  DemoMesh d = demo();
  const std::vector<float> lum = luminance_plane(d.texture);
  for (bool repeat : {false, true})
    for (uint32_t channels : {1u, 3u}) {
      const std::vector<float>& tex = channels == 1 ? lum : d.texture.pixels;
      auto desc = render_desc(d, tex, channels, 72, repeat);
      auto a = cpu->render_mesh(desc), b = vk->render_mesh(desc);
      REQUIRE(a.count == 20);
      REQUIRE(a.coverage == b.coverage);  // coverage exact
      size_t covered = 0;
      for (uint32_t c : a.coverage) covered += c != engine::kNoMeshTriangle;
      CHECK(covered > a.coverage.size() / 20);
      CHECK(covered < a.coverage.size());
      float worst = 0;
      for (size_t k = 0; k < a.pixels.size(); ++k) worst = std::max(worst, std::abs(a.pixels[k] - b.pixels[k]));
      INFO("repeat " << repeat << ", channels " << channels << ": max |cpu - vulkan| = " << worst);
      CHECK(worst <= 1e-5f);
      // Empty pixels are 0 in every channel.
      for (size_t k = 0; k < a.coverage.size(); ++k)
        if (a.coverage[k] == engine::kNoMeshTriangle)
          for (uint32_t c = 0; c < channels; ++c) REQUIRE(a.pixels[k * channels + c] == 0.0f);
    }
  CHECK(vk->validation_errors() == 0);
}

TEST_CASE("render_mesh: into reused storage, every pixel is the fresh render's, on both backends", "[eval][engine][vulkan]") {
  // Eval renders the same views at every cost into one MeshRenders: nothing of an earlier
  // render (another texture, more views, more channels, a larger image) may survive.
  DemoMesh d = demo();
  const std::vector<float> lum = luminance_plane(d.texture);
  std::vector<float> bright(d.texture.pixels.size(), 0.9f);
  std::vector<std::unique_ptr<engine::Engine>> engines;
  engines.push_back(engine::make_cpu_engine({}));
  try {
    engines.push_back(test::lavapipe());
  } catch (const engine::EngineError& e) {
    WARN("skipped the Vulkan half: no lavapipe: " << e.what());
  }
  for (auto& e : engines) {
    INFO(e->device().backend);
    auto big = render_desc(d, bright, 3, 96, false);  // every covered pixel 0.9, 3 channels
    auto small = render_desc(d, lum, 1, 72, true);
    small.cameras.resize(7);
    engine::MeshRenders reused;
    e->render_mesh(big, reused);
    const size_t capacity = reused.pixels.capacity();
    e->render_mesh(small, reused);
    const engine::MeshRenders fresh = e->render_mesh(small);
    CHECK(reused.pixels.capacity() == capacity);  // the storage was kept
    REQUIRE(reused.count == 7);
    CHECK(reused.coverage == fresh.coverage);
    CHECK(reused.pixels == fresh.pixels);
    e->render_mesh(big, reused);  // and back to the larger render
    CHECK(reused.pixels == e->render_mesh(big).pixels);
    CHECK(e->validation_errors() == 0);
  }
}

TEST_CASE("render_mesh: the nearer of two overlapping triangles wins, ties to the lower index", "[eval][engine]") {
  // Two parallel quads facing the camera (z = 0 and z = 0.5, the second nearer), each with
  // a constant texel of its own.
  const std::vector<float> pos = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0, -1, -1, .5f, 1, -1, .5f, 1, 1, .5f, -1, 1, .5f};
  const std::vector<float> uv = {0.25f, 0.5f, 0.25f, 0.5f, 0.25f, 0.5f, 0.25f, 0.5f,
                                 0.75f, 0.5f, 0.75f, 0.5f, 0.75f, 0.5f, 0.75f, 0.5f};
  const std::vector<uint32_t> ix = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7};
  const std::vector<float> tex = {0.2f, 0.8f};  // 2 x 1 luminance
  engine::MeshRenderDesc d;
  d.width = d.height = 32;
  // Orthographic-like camera looking down -z from z = 2 (clip w = 1): NDC = (x/2, y/2).
  d.cameras = {{0.5f, 0, 0, 0, 0, 0.5f, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1}};
  d.positions = pos.data(), d.vertex_count = 8, d.indices = ix.data(), d.triangle_count = 4, d.uvs = uv.data();
  d.texture = tex.data(), d.texture_width = 2, d.texture_height = 1;
  auto cpu = engine::make_cpu_engine({});
  // Equal depth everywhere (w = 1): the first quad's triangles win.
  auto r = cpu->render_mesh(d);
  for (uint32_t j = 10; j < 22; ++j)
    for (uint32_t i = 10; i < 22; ++i) {
      REQUIRE(r.coverage[j * 32 + i] < 2);
      REQUIRE(r.pixels[j * 32 + i] == Approx(0.2f));
    }
  // Depth from w: the second quad nearer (smaller w, larger 1/w).
  d.cameras = {{0.5f, 0, 0, 0, 0, 0.5f, 0, 0, 0, 0, 0, 0, 0, 0, -0.5f, 1}};
  r = cpu->render_mesh(d);
  REQUIRE(r.coverage[16 * 32 + 16] >= 2);
  REQUIRE(r.pixels[16 * 32 + 16] == Approx(0.8f));
}

TEST_CASE("area resize: identity copies, halving averages 2x2 blocks", "[eval]") {
  Image img;
  img.width = 4, img.height = 2, img.channels = 1;
  img.pixels = {0, 1, 2, 3, 4, 5, 6, 7};
  auto same = eval::resize_area(img, 4, 2);
  CHECK(same.pixels == img.pixels);
  auto half = eval::resize_area(img, 2, 1);
  REQUIRE(half.pixels.size() == 2);
  CHECK(half.pixels[0] == Approx(2.5));
  CHECK(half.pixels[1] == Approx(4.5));
  auto third = eval::resize_area(img, 3, 2);  // fractional box weights keep the mean
  double m0 = 0, m1 = 0;
  for (float v : img.pixels) m0 += v;
  for (float v : third.pixels) m1 += v;
  CHECK(m1 / 6 == Approx(m0 / 8));
}

namespace {

// An independent Lanczos-3 resize in double precision: separable, output texel k centred
// at (k + 0.5) s - 0.5 input texels (s = input / output size), kernel stretched by s when
// shrinking, weights normalized to sum 1, taps outside the image read the edge texel.
std::vector<double> lanczos3_reference(const std::vector<double>& in, uint32_t w, uint32_t h, uint32_t W, uint32_t H) {
  auto L = [](double x) {
    x = std::abs(x);
    if (x < 1e-12) return 1.0;
    if (x >= 3) return 0.0;
    const double px = M_PI * x;
    return 3 * std::sin(px) * std::sin(px / 3) / (px * px);
  };
  auto axis = [&](uint32_t from, uint32_t to) {
    std::vector<std::vector<std::pair<uint32_t, double>>> taps(to);
    const double s = double(from) / to, stretch = std::max(1.0, s);
    for (uint32_t k = 0; k < to; ++k) {
      const double c = (k + 0.5) * s - 0.5;
      double sum = 0;
      for (int i = int(std::floor(c - 3 * stretch)); i <= int(std::ceil(c + 3 * stretch)); ++i) {
        const double wgt = L((i - c) / stretch);
        if (wgt != 0) taps[k].push_back({uint32_t(std::clamp(i, 0, int(from) - 1)), wgt}), sum += wgt;
      }
      for (auto& t : taps[k]) t.second /= sum;
    }
    return taps;
  };
  auto tx = axis(w, W), ty = axis(h, H);
  std::vector<double> rows(size_t(h) * W, 0.0), out(size_t(W) * H, 0.0);
  for (uint32_t j = 0; j < h; ++j)
    for (uint32_t i = 0; i < W; ++i)
      for (auto [x, wgt] : tx[i]) rows[size_t(j) * W + i] += wgt * in[size_t(j) * w + x];
  for (uint32_t j = 0; j < H; ++j)
    for (uint32_t i = 0; i < W; ++i)
      for (auto [y, wgt] : ty[j]) out[size_t(j) * W + i] += wgt * rows[size_t(y) * W + i];
  return out;
}

Image grey(uint32_t w, uint32_t h, const std::function<double(uint32_t, uint32_t)>& f) {
  Image img;
  img.width = w, img.height = h, img.channels = 1;
  for (uint32_t j = 0; j < h; ++j)
    for (uint32_t i = 0; i < w; ++i) img.pixels.push_back(float(f(i, j)));
  return img;
}

}  // namespace

TEST_CASE("Lanczos-3 resize matches a double-precision separable Lanczos-3", "[eval]") {
  // A smooth field with detail near the Nyquist limit, kept inside [0.1, 0.9] so the
  // clamp to [0,1] never acts.
  Image img = grey(37, 29, [](uint32_t i, uint32_t j) {
    return 0.5 + 0.25 * std::sin(0.37 * i + 0.11 * j) + 0.12 * std::cos(1.9 * i * 0.5 + 2.3 * j * 0.4);
  });
  std::vector<double> in(img.pixels.begin(), img.pixels.end());
  for (auto [W, H] : std::vector<std::pair<uint32_t, uint32_t>>{{18, 14}, {11, 20}, {7, 5}, {50, 41}}) {
    auto ours = eval::resize_lanczos3(img, W, H, false);
    REQUIRE(ours.width == W);
    REQUIRE(ours.height == H);
    REQUIRE(ours.channels == 1);
    auto ref = lanczos3_reference(in, img.width, img.height, W, H);
    double worst = 0, box_worst = 0;
    auto box = eval::resize_area(img, W, H);
    for (size_t k = 0; k < ref.size(); ++k)
      worst = std::max(worst, std::abs(ours.pixels[k] - ref[k])), box_worst = std::max(box_worst, std::abs(box.pixels[k] - ref[k]));
    INFO(W << "x" << H << ": max |ours - reference| = " << worst << ", box filter: " << box_worst);
    CHECK(worst < 1e-6);  // fp32 output against double: measured < 1e-7
    CHECK(box_worst > 4 * worst);  // the test tells Lanczos from a box filter
  }
  // The same size copies exactly.
  CHECK(eval::resize_lanczos3(img, 37, 29, true).pixels == img.pixels);
}

TEST_CASE("Lanczos-3 resize is OpenImageIO's ImageBufAlgo::resize \"lanczos3\" (what it replaced)", "[eval]") {
  // Noise (every frequency), 3 channels, shrunk by the ratios eval and reparam use (and
  // more than 10x, non-integer), and enlarged; OpenImageIO accumulates in float and takes
  // a filter evaluated in float, so the two agree to float rounding, not bit for bit.
  Image img;
  img.width = 203, img.height = 157, img.channels = 3;
  uint32_t seed = 7;
  for (size_t k = 0; k < size_t(203) * 157 * 3; ++k) {
    seed = seed * 1664525u + 1013904223u;
    img.pixels.push_back(float((seed >> 8) % 256) / 255.0f);
  }
  for (auto [W, H] : std::vector<std::pair<uint32_t, uint32_t>>{{143, 111}, {101, 78}, {64, 50}, {17, 13}, {290, 201}}) {
    const OIIO::ImageBuf source(OIIO::ImageSpec(int(img.width), int(img.height), 3, OIIO::TypeDesc::FLOAT), img.pixels.data());
    OIIO::ImageBuf dest(OIIO::ImageSpec(int(W), int(H), 3, OIIO::TypeDesc::FLOAT));
    REQUIRE(OIIO::ImageBufAlgo::resize(dest, source, "lanczos3"));
    std::vector<float> ref(size_t(W) * H * 3);
    REQUIRE(dest.get_pixels(OIIO::ROI(0, int(W), 0, int(H), 0, 1, 0, 3), OIIO::TypeDesc::FLOAT, ref.data()));
    const Image ours = eval::resize_lanczos3(img, W, H, false);
    double worst = 0;
    for (size_t k = 0; k < ref.size(); ++k) worst = std::max(worst, double(std::abs(ours.pixels[k] - std::clamp(ref[k], 0.0f, 1.0f))));
    INFO(W << "x" << H << ": max |ours - OpenImageIO| = " << worst);
    CHECK(worst < 5e-5);  // measured <= 1.9e-5
  }
}

TEST_CASE("Lanczos-3 resize: constants stay, linear light averages light, alpha stays linear, rings are clamped", "[eval]") {
  Image flat;
  flat.width = 16, flat.height = 12, flat.channels = 4;
  for (size_t k = 0; k < 16 * 12; ++k) flat.pixels.insert(flat.pixels.end(), {0.2f, 0.6f, 0.9f, 0.7f});
  for (bool linear : {false, true}) {
    auto r = eval::resize_lanczos3(flat, 5, 7, linear);
    for (size_t k = 0; k < r.pixels.size(); ++k) CHECK(r.pixels[k] == Approx(flat.pixels[k % 4]).margin(2e-4));
  }
  // Black and white columns two texels wide, halved: the stored values average to 0.5, the
  // light to 0.5 (sRGB 0.7354); the alpha columns (0 and 1) average to 0.5 either way.
  Image stripes;
  stripes.width = 64, stripes.height = 8, stripes.channels = 2;
  for (uint32_t j = 0; j < 8; ++j)
    for (uint32_t i = 0; i < 64; ++i) {
      const float v = (i / 2) % 2 ? 1.0f : 0.0f;
      stripes.pixels.insert(stripes.pixels.end(), {v, v});
    }
  auto quarter = [](const Image& img, bool linear) { return eval::resize_lanczos3(img, img.width / 4, img.height, linear); };
  auto s = quarter(stripes, false), l = quarter(stripes, true);
  for (uint32_t i = 2; i < s.width - 2; ++i) {  // away from the edges
    CHECK(s.at(i, 4, 0) == Approx(0.5).margin(0.02));
    CHECK(l.at(i, 4, 0) == Approx(0.7354).margin(0.02));
    CHECK(s.at(i, 4, 1) == Approx(0.5).margin(0.02));
    CHECK(l.at(i, 4, 1) == Approx(0.5).margin(0.02));
  }
  // A hard step rings (values past 0 and 1 before the clamp): nothing leaves [0,1].
  Image step = grey(32, 4, [](uint32_t i, uint32_t) { return i < 16 ? 0.0 : 1.0; });
  for (bool linear : {false, true}) {
    auto r = eval::resize_lanczos3(step, 45, 4, linear);
    for (float v : r.pixels) CHECK((v >= 0.0f && v <= 1.0f));
  }
}

TEST_CASE("savings: a curve reaching every q at half the cost saves half the pixels", "[eval]") {
  std::vector<std::pair<double, double>> b, a;
  for (double c : {0.1, 0.2, 0.4, 0.8}) b.push_back({c, 0.01 / c}), a.push_back({c, 0.005 / c});
  auto s = eval::pixel_ratio_at_equal_q(a, b);
  REQUIRE(s.points >= 2);
  CHECK(s.ratio == Approx(0.5).epsilon(1e-9));
  auto t = eval::pixel_ratio_at_equal_q(b, a);
  CHECK(t.ratio == Approx(2.0).epsilon(1e-9));
  std::vector<std::pair<double, double>> far = {{0.1, 1e-6}, {0.2, 1e-7}};
  CHECK(eval::pixel_ratio_at_equal_q(far, b).points == 0);
  // A nearly flat curve (q 1.0e-3 .. 0.9e-3) a hair below another: equal-q costs say "a
  // third of the pixels", but the two never differ by more than the noise floor (2e-5):
  // every level is a tie and the ratio is 1. With a smaller floor the ratio stands.
  std::vector<std::pair<double, double>> flat_b, flat_a;
  for (double c : {0.2, 0.4, 0.6, 0.8}) flat_b.push_back({c, 1.0e-3 - 1.25e-4 * c}), flat_a.push_back({c, 0.99e-3 - 1.25e-4 * c});
  auto naive = eval::pixel_ratio_at_equal_q(flat_a, flat_b);
  REQUIRE(naive.points >= 2);
  CHECK(naive.ratio < 0.95);
  auto floored = eval::pixel_ratio_at_equal_q(flat_a, flat_b, 2e-5);
  CHECK(floored.points == naive.points);
  CHECK(floored.ties == floored.points);
  CHECK(floored.ratio == Approx(1.0));
  CHECK(eval::pixel_ratio_at_equal_q(flat_a, flat_b, 1e-6).ties == 0);
  CHECK(eval::pixel_ratio_at_equal_q(flat_a, flat_b, 1e-6).ratio == Approx(naive.ratio));
  // Far apart curves are untouched by a floor well below their gap.
  CHECK(eval::pixel_ratio_at_equal_q(a, b, 1e-4).ratio == Approx(0.5).epsilon(1e-9));
}

TEST_CASE("eval: a layout against itself at c_r = 1 gives q = 0, q_r falls as c_r rises", "[eval]") {
  io::GltfFile file = pipeline::make_demo_asset();
  auto cpu = engine::make_cpu_engine({});
  eval::EvalOptions o;
  // Views that resolve the texture (auto: 1536 px for the demo's 512^2): at 128 px the 20
  // views minify it about 4x, trilinear filtering averages c_r 0.1 and 0.3 alike and q is
  // sampling phase (0.0067 at 0.1, 0.0072 at 0.3). This test never ran in CI until the
  // ';' in its name was fixed, so it did not see that eval's default moved to trilinear.
  o.cost_grid = {0.1, 0.3, 1.0};
  o.artifacts = false;
  o.noise_floor = false;
  const eval::EvalResult r = eval::evaluate(file, {}, *cpu, o);
  REQUIRE(r.views == 20);
  CHECK(r.resolution.resolved_fraction >= 0.95);
  const auto& curve = r.layouts[0].curve;
  REQUIRE(curve.size() == 3);
  // Same texture, same UVs, same renders: GMSD of identical images is exactly 0 (tolerance
  // 1e-12 only guards the printing).
  CHECK(curve[2].q <= 1e-12);
  CHECK(curve[2].width == 512);
  CHECK(curve[0].q > curve[1].q);
  CHECK(curve[1].q > curve[2].q);
  CHECK(curve[0].c_r_actual == Approx(0.1).epsilon(0.02));
  // Costs are image texels; the input is resized as users do, the stronger variant kept.
  CHECK(r.to_json()["cost_measure"] == "image_texels");
  const auto& L = r.layouts[0];
  REQUIRE(L.resize == r.input_resize);
  REQUIRE(L.resize_mean_log_q);
  const auto [srgb, linear] = *L.resize_mean_log_q;
  CHECK(L.resize == (linear < srgb ? "lanczos3-linear" : "lanczos3-srgb"));
  CHECK(std::min(srgb, linear) == Approx(std::log(std::max(curve[0].q, 1e-9)) / 3 +
                                         std::log(std::max(curve[1].q, 1e-9)) / 3 +
                                         std::log(std::max(curve[2].q, 1e-9)) / 3));
  CHECK(!L.as_written);  // the reference is not scored against itself
}

TEST_CASE("eval: the paper's baseline re-bakes the input layout and area-filters it", "[eval]") {
  io::GltfFile file = pipeline::make_demo_asset({16, 128});
  auto cpu = engine::make_cpu_engine({});
  eval::EvalOptions o = two_costs();
  o.paper_baseline = true;
  const eval::EvalResult r = eval::evaluate(file, {}, *cpu, o);
  REQUIRE(r.layouts.size() == 2);
  const auto& L = r.layouts[1];
  CHECK(L.name == "input-rebaked");
  CHECK(L.texture == "rebaked");
  CHECK(L.resize == "area");
  CHECK(L.curve[1].q < 1e-3);  // an identity re-bake at the same size is (nearly) exact
  // At a quarter of the texels the area filter differs from the Lanczos resize.
  CHECK(L.curve[0].q != r.layouts[0].curve[0].q);
  bool vs_paper = false;
  for (const auto& sv : r.savings) vs_paper = vs_paper || sv.vs == "input-rebaked";
  CHECK(!vs_paper);  // nothing but the input to set against it here
  CHECK(r.savings.size() == 1);
}

TEST_CASE("eval: a file is scored as written, at its own texture's real size", "[eval]") {
  io::GltfFile file = pipeline::make_demo_asset({16, 128});
  auto cpu = engine::make_cpu_engine({});
  eval::EvalOptions o = two_costs();
  // The same asset: q = 0 at c_r = 1.
  auto same = eval::score_as_written(file, file, *cpu, o);
  CHECK(same.c_r == 1.0);
  CHECK(same.c_r_chart == Approx(1.0));
  CHECK(same.q <= 1e-12);
  // The asset with its texture halved a side by a user's resize: c_r = 0.25, and q is the
  // input curve's point there (up to the 8-bit rounding of the written PNG).
  const eval::EvalResult full = eval::evaluate(file, {}, *cpu, o);
  const bool linear = full.input_resize == "lanczos3-linear";
  io::GltfFile half = file;
  half.path = "half.glb";
  Image img = io::decode_image(file.image_bytes[0], "demo");
  Image small = eval::resize_lanczos3(img, img.width / 2, img.height / 2, linear);
  small.bits = 8;
  half.image_bytes[0] = io::encode_image(small, "png");
  auto scored = eval::score_as_written(file, half, *cpu, o);
  CHECK(scored.c_r == Approx(0.25));
  CHECK(scored.c_r_chart == Approx(0.25));
  const double q_curve = full.layouts[0].curve[0].q;
  REQUIRE(q_curve > 0);
  CHECK(scored.q == Approx(q_curve).epsilon(0.05));
  // evaluate reports the same point for the file, beside its re-baked curve.
  const eval::EvalResult r = eval::evaluate(file, {{"half", &half}}, *cpu, o);
  REQUIRE(r.layouts.size() == 2);
  REQUIRE(r.layouts[1].as_written);
  const auto& aw = *r.layouts[1].as_written;
  CHECK(aw.c_r == Approx(scored.c_r));
  CHECK(aw.q == Approx(scored.q).epsilon(1e-9));
  CHECK(aw.width == img.width / 2);
  // Its curve re-bakes the reference's full texture, so at c_r = 1 it is near lossless.
  CHECK(r.layouts[1].curve[1].q < 0.02);
}

TEST_CASE("eval: the isometric layout and another file of the same mesh, report and savings", "[eval]") {
  io::GltfFile file = pipeline::make_demo_asset({16, 128});
  io::GltfFile copy = file;
  copy.path = "copy.glb";
  auto cpu = engine::make_cpu_engine({});
  eval::EvalOptions o;
  o.resolution = 64;
  o.cost_grid = {0.2, 0.5, 1.0};
  o.flatten = true;
  o.thumbnail = 32;
  eval::EvalArtifacts art;
  const eval::EvalResult r = eval::evaluate(file, {{"copy", &copy}}, *cpu, o, &art);
  REQUIRE(r.layouts.size() == 3);
  CHECK(r.layouts[1].name == "copy");
  CHECK(r.layouts[1].texture == "rebaked");
  CHECK(r.layouts[2].name == "flatten");
  for (const auto& L : r.layouts)
    for (const auto& p : L.curve) CHECK(p.q >= 0);
  // A re-bake of the same layout at the same size is close to the original.
  CHECK(r.layouts[1].curve[2].q < 0.02);
  REQUIRE(r.savings.size() >= 2);
  // The report: every savings row names both layouts and the ratio (null when the curves
  // share no q range).
  const auto report = r.to_json();
  for (const auto& s : report["savings"]) {
    CHECK(s.contains("layout"));
    CHECK(s.contains("vs"));
    CHECK(s.contains("pixel_ratio_at_equal_q"));
  }
  // Image texels: every layout's texture at c_r = 1 has the reference's W x H; the paper's
  // chart cost differs by the layouts' UV areas.
  for (const auto& L : r.layouts) {
    const auto& p = L.curve[2];
    CHECK(double(p.width) * p.height == Approx(128.0 * 128.0).epsilon(0.02));
    CHECK(p.c_r_chart == Approx(p.c_r_actual * L.uv_area / r.reference.uv_area));
  }
  CHECK(r.layouts[2].uv_area != Approx(r.layouts[0].uv_area));
  // The copy as written is the reference itself.
  REQUIRE(r.layouts[1].as_written);
  CHECK(r.layouts[1].as_written->c_r == 1.0);
  CHECK(r.layouts[1].as_written->q <= 1e-12);
  CHECK(!r.layouts[2].as_written);
  CHECK(art.layouts.size() == 3);
  CHECK(art.reference_contact.width == 5 * 32);
}

TEST_CASE("eval --cost-axis bytes: each point's texture encoded as the input's image is, savings in bytes", "[eval]") {
  io::GltfFile file = pipeline::make_demo_asset({16, 128});
  auto cpu = engine::make_cpu_engine({});
  eval::EvalOptions o = two_costs();
  o.cost_axis = eval::CostAxis::Bytes;
  const std::vector<uint8_t>& in_bytes = file.image_bytes[0];
  const io::EncodeSettings settings = io::encode_settings_of(in_bytes);
  const Image img = io::decode_image(in_bytes, "demo");
  REQUIRE(img.channels == 3);
  // A user's file: the texture halved a side, written as the input was.
  io::GltfFile half = file;
  half.path = "half.glb";
  half.image_bytes[0] = io::encode_image(eval::resize_lanczos3(img, 64, 64, false), settings);
  const eval::EvalResult r = eval::evaluate(file, {{"half", &half}}, *cpu, o);
  CHECK(r.cost_axis == eval::CostAxis::Bytes);
  CHECK(r.reference.image_bytes == in_bytes.size());
  CHECK(r.reference.encoding == io::describe(settings));
  // The input's points: its texture resized as the curve resizes it, encoded with the
  // input's settings, byte for byte the size of that encoding.
  const bool linear = r.input_resize == "lanczos3-linear";
  const auto& curve = r.layouts[0].curve;
  REQUIRE(curve.size() == 2);
  for (const auto& p : curve) {
    INFO("c_r " << p.c_r);
    Image resized = eval::resize_lanczos3(img, p.width, p.height, linear);
    resized.bits = img.bits;
    REQUIRE(p.bytes);
    CHECK(*p.bytes == io::encode_image(resized, settings).size());
    CHECK(p.bytes_ratio == Approx(double(*p.bytes) / double(in_bytes.size())));
  }
  CHECK(*curve[0].bytes < *curve[1].bytes);  // a quarter of the texels, fewer bytes
  // The file as written counts its own image's bytes.
  const auto& other = r.layouts[1];
  REQUIRE(other.as_written);
  REQUIRE(other.as_written->bytes);
  CHECK(*other.as_written->bytes == half.image_bytes[0].size());
  CHECK(other.as_written->bytes_ratio == Approx(double(half.image_bytes[0].size()) / double(in_bytes.size())));
  // Along bytes a curve is its cheapest points: one that costs more and looks no better
  // than a cheaper one is left out (texels keep every point).
  eval::LayoutResult made;
  made.curve.resize(3);
  made.curve[0].c_r_actual = 0.25, made.curve[0].bytes_ratio = 0.6, made.curve[0].q = 0.02;
  made.curve[1].c_r_actual = 0.5, made.curve[1].bytes_ratio = 1.2, made.curve[1].q = 0.01;
  made.curve[2].c_r_actual = 1.0, made.curve[2].bytes_ratio = 0.9, made.curve[2].q = 0.0;
  CHECK(made.cost_q(eval::CostAxis::Texels).size() == 3);
  CHECK(made.cost_q(eval::CostAxis::Bytes) == std::vector<std::pair<double, double>>{{0.6, 0.02}, {0.9, 0.0}});
  // The savings compare the curves at equal q along bytes, not texels.
  REQUIRE(r.savings.size() == 1);
  const eval::Savings by_bytes = eval::pixel_ratio_at_equal_q(other.cost_q(eval::CostAxis::Bytes),
                                                              r.layouts[0].cost_q(eval::CostAxis::Bytes), r.noise_floor());
  REQUIRE(by_bytes.points > 0);
  CHECK(r.savings[0].savings.points == by_bytes.points);
  CHECK(r.savings[0].savings.ratio == Approx(by_bytes.ratio));
  const auto report = r.to_json();
  CHECK(report["cost_axis"] == "bytes");
  CHECK(report["reference"]["image_bytes"] == in_bytes.size());
  CHECK(report["savings"][0].contains("bytes_ratio_at_equal_q"));
  CHECK(!report["savings"][0].contains("pixel_ratio_at_equal_q"));
  CHECK(report["layouts"][0]["curve"][0]["bytes"] == *curve[0].bytes);
  // A JPEG input: its points are JPEGs at its quality and subsampling, not PNGs.
  io::GltfFile jpeg = file;
  io::EncodeSettings q70;
  q70.format = "jpeg", q70.jpeg_quality = 70, q70.jpeg_h_sampling = 1, q70.jpeg_v_sampling = 1;
  jpeg.image_bytes[0] = io::encode_image(img, q70);
  jpeg.model.images[0].mimeType = "image/jpeg";
  const Image jimg = io::decode_image(jpeg.image_bytes[0], "demo.jpg");
  const eval::EvalResult j = eval::evaluate(jpeg, {}, *cpu, o);
  CHECK(j.reference.encoding == io::describe(io::encode_settings_of(jpeg.image_bytes[0])));
  const auto& jp = j.layouts[0].curve[0];
  Image jresized = eval::resize_lanczos3(jimg, jp.width, jp.height, j.input_resize == "lanczos3-linear");
  jresized.bits = jimg.bits;
  REQUIRE(jp.bytes);
  CHECK(*jp.bytes == io::encode_image(jresized, io::encode_settings_of(jpeg.image_bytes[0])).size());
  CHECK(*jp.bytes < io::encode_image(jresized, settings).size() / 2);  // far below the PNG's
  // The texel axis carries no bytes; a codec's fixed-rate blocks go with texels, so the two
  // together are refused.
  o.cost_axis = eval::CostAxis::Texels;
  const eval::EvalResult t = eval::evaluate(file, {}, *cpu, o);
  CHECK(!t.layouts[0].curve[0].bytes);
  CHECK(!t.to_json()["layouts"][0]["curve"][0].contains("bytes"));
  CHECK(t.to_json()["cost_axis"] == "texels");
  o.cost_axis = eval::CostAxis::Bytes;
  o.codec = io::AstcOptions{6, 6, io::AstcQuality::Fastest};
  CHECK_THROWS_AS(eval::evaluate(file, {}, *cpu, o), InputError);
}

TEST_CASE("eval: a file of another mesh is an input error", "[eval]") {
  io::GltfFile a = pipeline::make_demo_asset({16, 64}), b = pipeline::make_demo_asset({8, 64});
  b.path = "other.glb";
  auto cpu = engine::make_cpu_engine({});
  eval::EvalOptions o;
  o.resolution = 32;
  o.cost_grid = {1.0};
  CHECK_THROWS_AS(eval::evaluate(a, {{"other", &b}}, *cpu, o), InputError);
}
