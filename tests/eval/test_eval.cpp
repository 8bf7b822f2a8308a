// eval: whole-mesh renders on both backends, q-c curves, savings, and the HTML report.
#include <catch2/catch.hpp>

#include "core/error.h"
#include "engine.h"
#include "eval/eval.h"
#include "io/asset.h"
#include "io/atomic_file.h"
#include "io/image_io.h"
#include "perceptual/triangle_view.h"
#include "pipeline/demo_asset.h"
#include "support.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>

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

std::unique_ptr<engine::Engine> lavapipe() {
  engine::EngineOptions o;
  o.validation = true;
  return engine::make_vulkan_engine(engine::DeviceRequest::Lavapipe, o);
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
  std::unique_ptr<engine::Engine> vk;
  try {
    vk = lavapipe();
  } catch (const engine::EngineError& e) {
    UVPRESS_SKIP(std::string("no lavapipe: ") + e.what());
  }
  auto cpu = engine::make_cpu_engine({});
  DemoMesh d = demo();
  const std::vector<float> lum = perceptual::luminance_plane(d.texture);
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
}

TEST_CASE("eval: a layout against itself at c_r = 1 gives q = 0; q_r falls as c_r rises", "[eval]") {
  io::GltfFile file = pipeline::make_demo_asset();
  auto cpu = engine::make_cpu_engine({});
  eval::EvalOptions o;
  o.resolution = 128;
  o.cost_grid = {0.1, 0.3, 1.0};
  o.artifacts = false;
  auto r = eval::evaluate(file, {}, *cpu, o);
  REQUIRE(r["views"] == 20);
  const auto& curve = r["layouts"][0]["curve"];
  REQUIRE(curve.size() == 3);
  // Same texture, same UVs, same renders: GMSD of identical images is exactly 0 (tolerance
  // 1e-12 only guards the printing).
  CHECK(curve[2]["q"].get<double>() <= 1e-12);
  CHECK(curve[2]["width"] == 512);
  CHECK(curve[0]["q"].get<double>() > curve[1]["q"].get<double>());
  CHECK(curve[1]["q"].get<double>() > curve[2]["q"].get<double>());
  CHECK(curve[0]["c_r_actual"].get<double>() == Approx(0.1).epsilon(0.02));
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
  auto r = eval::evaluate(file, {{"copy", &copy}}, *cpu, o, &art);
  REQUIRE(r["layouts"].size() == 3);
  CHECK(r["layouts"][1]["name"] == "copy");
  CHECK(r["layouts"][1]["texture"] == "rebaked");
  CHECK(r["layouts"][2]["name"] == "flatten");
  for (const auto& L : r["layouts"])
    for (const auto& p : L["curve"]) CHECK(p["q"].get<double>() >= 0);
  // A re-bake of the same layout at the same size is close to the original.
  CHECK(r["layouts"][1]["curve"][2]["q"].get<double>() < 0.02);
  REQUIRE(r["savings"].size() >= 2);
  for (const auto& s : r["savings"]) {
    CHECK(s.contains("layout"));
    CHECK(s.contains("vs"));
    CHECK(s.contains("pixel_ratio_at_equal_q"));
  }
  CHECK(art.layouts.size() == 3);
  CHECK(art.reference_contact.width == 5 * 32);
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

TEST_CASE("eval CLI: report JSON and an HTML report that loads in headless Chromium", "[eval][cli]") {
  test::Scratch dir("eval-cli");
  io::GltfFile small = pipeline::make_demo_asset({16, 128});
  io::save_gltf(small, (dir / "small.glb").string());
  auto res = test::run_uvpress("eval " + (dir / "small.glb").string() + " --flatten --device cpu --resolution 64 "
                               "--cost-grid 0.2,0.5,1 --report " + (dir / "r.json").string() + " --html " +
                               (dir / "html").string());
  INFO(res.err);
  REQUIRE(res.exit_code == 0);
  std::ifstream jf(dir / "r.json");
  auto r = nlohmann::json::parse(jf);
  for (const char* key : {"asset", "device", "views", "layouts", "savings"}) CHECK(r.contains(key));
  for (const auto& L : r["layouts"]) {
    CHECK(L.contains("name"));
    CHECK(L.contains("file"));
    for (const auto& p : L["curve"]) CHECK((p.contains("c_r") && p.contains("r") && p.contains("q")));
  }
  // Every file the page refers to is there (offline: relative names only).
  std::ifstream hf(dir / "html" / "index.html");
  std::stringstream buffer;
  buffer << hf.rdbuf();
  const std::string html = buffer.str();
  std::regex src("src=\"([^\"]+)\"");
  size_t refs = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), src); it != std::sregex_iterator(); ++it) {
    const std::string name = (*it)[1];
    CHECK(name.find(':') == std::string::npos);
    CHECK(test::fs::exists(dir / "html" / name));
    ++refs;
  }
  CHECK(refs >= 5);
  CHECK(html.find("<script") == std::string::npos);
  // Bad input: a missing file is exit 1 with the file named.
  auto bad = test::run_uvpress("eval " + (dir / "missing.glb").string());
  CHECK(bad.exit_code == 1);

  if (!test::fs::exists("/usr/bin/chromium")) UVPRESS_SKIP("/usr/bin/chromium is absent");
  const auto profile = dir / "profile";
  test::fs::create_directories(profile);
  const auto shot = dir / "shot.png";
  const std::string cmd = "timeout 60 /usr/bin/chromium --headless --no-sandbox --disable-gpu --disable-quic "
                          "--no-first-run --disable-background-networking --disable-component-update --disable-sync "
                          "--user-data-dir=" + profile.string() + " --window-size=1200,1600 --screenshot=" +
                          shot.string() + " --enable-logging=stderr --v=0 file://" +
                          (dir / "html" / "index.html").string() + " >" + (dir / "log.txt").string() + " 2>&1";
  const int rc = std::system(cmd.c_str());
  std::ifstream lf(dir / "log.txt");
  std::stringstream log;
  log << lf.rdbuf();
  INFO(log.str());
  REQUIRE(rc == 0);
  CHECK(log.str().find("ERR_FILE_NOT_FOUND") == std::string::npos);
  CHECK(log.str().find("Uncaught") == std::string::npos);
  REQUIRE(test::fs::exists(shot));
  Image img = io::decode_image(io::read_file(shot.string()), "screenshot");
  double sum = 0, sum2 = 0;
  const size_t n = img.pixels.size();
  for (float v : img.pixels) sum += v, sum2 += double(v) * v;
  const double var = sum2 / double(n) - (sum / double(n)) * (sum / double(n));
  CHECK(var > 1e-3);  // not blank
}
