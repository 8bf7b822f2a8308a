// `uvpress eval` as a user runs it: the report JSON and an HTML report that loads in
// headless Chromium, a missing file as an input error, and --shading (lit by default on a
// normal-mapped asset, unlit on request, bad values as usage errors).
#include <catch2/catch.hpp>

#include "core/image.h"
#include "eval/bumpy_sheet.h"
#include "io/atomic_file.h"
#include "io/gltf_io.h"
#include "io/image_io.h"
#include "pipeline/demo_asset.h"
#include "support.h"

#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

using namespace uvpress;
using test::bumpy_sheet;

TEST_CASE("eval CLI: report JSON and an HTML report that loads in headless Chromium", "[eval][cli]") {
  test::Scratch dir("eval-cli");
  io::GltfFile small = pipeline::make_demo_asset({16, 128});
  io::save_gltf(small, (dir / "small.glb").string());
  io::save_gltf(small, (dir / "other.glb").string());
  auto res = test::run_uvpress("eval " + (dir / "small.glb").string() + " " + (dir / "other.glb").string() +
                               " --flatten --paper-baseline --device cpu --resolution 64 "
                               "--cost-grid 0.2,0.5,1 --report " + (dir / "r.json").string() + " --html " +
                               (dir / "html").string());
  INFO(res.err);
  REQUIRE(res.exit_code == 0);
  std::ifstream jf(dir / "r.json");
  auto r = nlohmann::json::parse(jf);
  for (const char* key : {"asset", "device", "views", "layouts", "savings", "cost_measure", "input_resize"})
    CHECK(r.contains(key));
  REQUIRE(r["layouts"].size() == 4);  // input, input-rebaked, other, flatten
  CHECK(r["layouts"][1]["name"] == "input-rebaked");
  CHECK(r["layouts"][2].contains("as_written"));
  CHECK(res.out.find("other as written: c_r 1.000") != std::string::npos);
  CHECK(res.out.find("image texels") != std::string::npos);
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

TEST_CASE("uvpress eval --shading: lit by default on a normal-mapped asset, unlit on request, bad values are usage errors",
          "[eval][lit][cli]") {
  test::Scratch dir("eval-lit");
  io::save_gltf(bumpy_sheet(true, 64, 8), (dir / "bumpy.glb").string());
  const std::string common = " --cost-grid 0.5,1 --resolution 128 --device cpu --report ";
  auto r = test::run_uvpress("eval '" + (dir / "bumpy.glb").string() + "'" + common + "'" + (dir / "a.json").string() + "'");
  REQUIRE(r.exit_code == 0);
  CHECK(r.out.find(", lit)") != std::string::npos);
  std::ifstream in((dir / "a.json").string());
  const auto report = nlohmann::json::parse(in);
  CHECK(report["shading"] == "lit");
  CHECK(report["layouts"][0]["curve"][0].contains("q_unlit"));
  CHECK(report["layouts"][0]["curve"][0]["q"] == report["layouts"][0]["curve"][0]["q_lit"]);
  r = test::run_uvpress("eval '" + (dir / "bumpy.glb").string() + "' --shading unlit" + common + "'" +
                        (dir / "b.json").string() + "'");
  REQUIRE(r.exit_code == 0);
  std::ifstream in_b((dir / "b.json").string());
  CHECK(nlohmann::json::parse(in_b)["shading"] == "unlit");
  r = test::run_uvpress("eval '" + (dir / "bumpy.glb").string() + "' --shading glossy");
  CHECK(r.exit_code == 2);
  r = test::run_uvpress("reparam '" + (dir / "bumpy.glb").string() + "' -o '" + (dir / "o.glb").string() +
                        "' --score-shading glossy");
  CHECK(r.exit_code == 2);
}

TEST_CASE("uvpress eval --cost-axis bytes: savings and as-written costs in bytes, bad values are usage errors",
          "[eval][cli]") {
  test::Scratch dir("eval-bytes");
  io::GltfFile small = pipeline::make_demo_asset({16, 128});
  io::save_gltf(small, (dir / "small.glb").string());
  io::save_gltf(small, (dir / "other.glb").string());
  const std::string files = " '" + (dir / "small.glb").string() + "' '" + (dir / "other.glb").string() + "'";
  auto r = test::run_uvpress("eval" + files + " --cost-axis bytes --device cpu --resolution 64 --cost-grid 0.5,1 --report '" +
                             (dir / "r.json").string() + "' --html '" + (dir / "html").string() + "'");
  REQUIRE(r.exit_code == 0);
  INFO(r.out << r.err);
  CHECK(r.out.find("savings in bytes, encoded as png") != std::string::npos);
  CHECK(r.out.find("of the input's bytes)") != std::string::npos);  // the file as written
  std::ifstream in((dir / "r.json").string());
  const auto report = nlohmann::json::parse(in);
  CHECK(report["cost_axis"] == "bytes");
  const uint64_t image_bytes = report["reference"]["image_bytes"];
  CHECK(image_bytes == small.image_bytes[0].size());
  // The other file is the input itself: as written, exactly the input's bytes.
  CHECK(report["layouts"][1]["as_written"]["bytes"] == image_bytes);
  CHECK(report["layouts"][1]["as_written"]["bytes_ratio"] == 1.0);
  for (const auto& L : report["layouts"])
    for (const auto& p : L["curve"]) CHECK(p["bytes_ratio"].get<double>() == Approx(p["bytes"].get<double>() / double(image_bytes)));
  std::ifstream html((dir / "html" / "index.html").string());
  std::stringstream page;
  page << html.rdbuf();
  CHECK(page.str().find("Byte savings at equal quality") != std::string::npos);
  r = test::run_uvpress("eval" + files + " --cost-axis pixels --device cpu");
  CHECK(r.exit_code == 2);
  r = test::run_uvpress("eval" + files + " --cost-axis bytes --codec astc-6x6 --device cpu --resolution 32 --cost-grid 1");
  CHECK(r.exit_code == 2);  // a usage error: the codec's blocks go with texels
  CHECK(r.err.find("--cost-axis: bytes counts") != std::string::npos);
}
