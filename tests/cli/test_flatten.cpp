// `uvpress flatten` as a user runs it: OBJ and glTF in and out, report and log files,
// one-line errors with exit 1 for non-disk and malformed input, and the same bits whatever
// the thread count.
#include <catch2/catch.hpp>

#include "flatten/flatten.h"
#include "io/asset.h"
#include "io/gltf_append.h"
#include "io/gltf_io.h"
#include "io/vertex_attribute.h"
#include "io/mesh_io.h"
#include "pipeline/demo_asset.h"
#include "support.h"

#include <cmath>
#include <fstream>
#include <sstream>

using namespace uvpress;
using test::run_uvpress;

namespace {

using test::quoted;

// An n x n grid with a bump, as OBJ text; `skip` leaves out faces (to make holes).
std::string grid_obj(int n, const std::vector<int>& skip = {}) {
  std::ostringstream out;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      double x = double(i) / n, y = double(j) / n;
      out << "v " << x << ' ' << y << ' ' << 0.5 * std::exp(-((x - 0.5) * (x - 0.5) + (y - 0.5) * (y - 0.5)) / 0.05)
          << '\n';
    }
  int f = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i, ++f) {
      if (std::find(skip.begin(), skip.end(), f) != skip.end()) continue;
      int a = j * (n + 1) + i + 1, b = a + 1, c = a + n + 1, d = c + 1;
      out << "f " << a << ' ' << b << ' ' << d << "\nf " << a << ' ' << d << ' ' << c << '\n';
    }
  return out.str();
}



}  // namespace

TEST_CASE("flatten CLI: OBJ in, OBJ with vt out, report and logs", "[flatten][cli]") {
  test::Scratch dir("flatten-obj");
  std::ofstream(dir / "bump.obj") << grid_obj(12);
  auto r = run_uvpress("flatten " + quoted(dir / "bump.obj") + " -o " + quoted(dir / "flat.obj") + " --log " +
                       quoted(dir / "log.csv") + " --report " + quoted(dir / "report.json"));
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(r.err.empty());
  CHECK_THAT(r.out, Catch::Contains("288 triangles") && Catch::Contains("0 flips"));
  Mesh out = io::read_mesh((dir / "flat.obj").string());
  REQUIRE(out.has_uvs());
  CHECK(out.uv_triangles == out.triangles);
  double lo = 1, hi = 0;
  for (double x : out.uvs) lo = std::min(lo, x), hi = std::max(hi, x);
  CHECK(lo >= 0);
  CHECK(hi <= 1);
  CHECK(hi == Approx(1));
  CHECK(flatten::count_flips(out.uv_triangles, out.uvs) == 0);

  auto report = nlohmann::json::parse(test::read_file(dir / "report.json"));
  for (const char* key : {"method", "faces", "N_c", "eta", "t_c_s", "E_c", "s_per_iter", "flips", "peak_rss_mb"})
    CHECK(report.contains(key));
  CHECK(report["method"] == "progressive");
  CHECK(report["faces"] == 288);
  CHECK(report["flips"] == 0);
  CHECK(report["E_c"].get<double>() > 1);
  const int iterations = report["N_c"];
  // CSV: a header and one row per iteration, with the timing breakdown.
  std::istringstream csv(test::read_file(dir / "log.csv"));
  std::string header, line;
  std::getline(csv, header);
  CHECK_THAT(header, Catch::Contains("energy") && Catch::Contains("t_com") && Catch::Contains("t_factorization") &&
                         Catch::Contains("fraction_bounded") && Catch::Contains("phase"));
  int rows = 0;
  while (std::getline(csv, line)) rows += !line.empty();
  CHECK(rows == iterations);

  r = run_uvpress("flatten " + quoted(dir / "bump.obj") + " -o " + quoted(dir / "slim.obj") +
                  " --method slim --log " + quoted(dir / "log.json"));
  REQUIRE(r.exit_code == 0);
  auto log = nlohmann::json::parse(test::read_file(dir / "log.json"));
  REQUIRE(log["iterations"].size() > 0);
  CHECK(log["iterations"][0]["phase"] == "slim");
  CHECK(log["iterations"][0].contains("t_line_search"));
}

TEST_CASE("flatten CLI: glTF in, a new TEXCOORD set out, valid", "[flatten][cli]") {
  test::Scratch dir("flatten-gltf");
  io::save_gltf(pipeline::make_demo_asset({16, 32}), (dir / "demo.glb").string());
  auto r = run_uvpress("flatten " + quoted(dir / "demo.glb") + " -o " + quoted(dir / "flat.glb") + " --report " +
                       quoted(dir / "report.json"));
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  auto file = io::load_gltf((dir / "flat.glb").string());
  const auto& attributes = file.model.meshes[0].primitives[0].attributes;
  CHECK(attributes.count("TEXCOORD_0"));
  REQUIRE(attributes.count("TEXCOORD_1"));
  CHECK(test::validate_gltf(dir / "flat.glb")["numErrors"] == 0);
  auto report = nlohmann::json::parse(test::read_file(dir / "report.json"));
  CHECK(report["faces"] == 512);
  CHECK(report["flips"] == 0);
}

TEST_CASE("flatten CLI: non-disk, empty, NaN and unsupported inputs exit 1 with one line", "[flatten][cli]") {
  test::Scratch dir("flatten-bad");
  std::ofstream(dir / "holes.obj") << grid_obj(6, {14, 22});  // two holes: 3 boundary loops
  std::ofstream(dir / "empty.obj") << "# nothing\n";
  std::ofstream(dir / "nan.obj") << "v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n";
  std::ofstream(dir / "two.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 0 0\nv 6 0 0\nv 5 1 0\nf 1 2 3\nf 4 5 6\n";
  std::ofstream(dir / "mesh.ply") << "ply\n";
  auto out = dir / "out.obj";
  test::check_input_error(dir, "flatten " + quoted(dir / "holes.obj") + " -o " + quoted(out), dir / "holes.obj",
              "3 boundary loops");
  test::check_input_error(dir, "flatten " + quoted(dir / "two.obj") + " -o " + quoted(out), dir / "two.obj",
              "2 connected components");
  test::check_input_error(dir, "flatten " + quoted(dir / "empty.obj") + " -o " + quoted(out), dir / "empty.obj", "no faces");
  test::check_input_error(dir, "flatten " + quoted(dir / "nan.obj") + " -o " + quoted(out), dir / "nan.obj", "non-finite");
  test::check_input_error(dir, "flatten " + quoted(dir / "mesh.ply") + " -o " + quoted(out), dir / "mesh.ply", "unsupported");
  test::check_input_error(dir, "flatten " + quoted(dir / "holes.obj") + " -o " + quoted(dir / "out.ply"), dir / "out.ply",
              "unsupported output format");
  CHECK(run_uvpress("flatten " + quoted(dir / "holes.obj") + " -o " + quoted(out) + " --method newton").exit_code == 2);
}

TEST_CASE("flatten CLI: a failed factorization exits 1 with the reason and writes nothing", "[flatten][cli]") {
  test::Scratch dir("flatten-fail");
  std::ofstream(dir / "bump.obj") << grid_obj(12);
  io::save_gltf(pipeline::make_demo_asset({16, 32}), (dir / "demo.glb").string());
  // check_input_error: exit 1, one stderr line naming the file and the reason, nothing on
  // stdout, no file written (output, report or log).
  for (const char* n : {"1", "3"})
    test::check_input_error(dir,
                            "flatten " + quoted(dir / "bump.obj") + " -o " + quoted(dir / "out.obj") + " --report " +
                                quoted(dir / "report.json") + " --log " + quoted(dir / "log.csv") +
                                " --test-break-factorization " + n,
                            dir / "bump.obj", "factorization failed: matrix not positive definite");
  test::check_input_error(dir,
                          "flatten " + quoted(dir / "demo.glb") + " -o " + quoted(dir / "out.glb") +
                              " --test-break-factorization 2",
                          dir / "demo.glb", "chart 0: factorization failed");

  // The same input without the hook converges for a legitimate reason, reported.
  auto r = run_uvpress("flatten " + quoted(dir / "bump.obj") + " -o " + quoted(dir / "out.obj") + " --report " +
                       quoted(dir / "report.json"));
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  auto report = nlohmann::json::parse(test::read_file(dir / "report.json"));
  CHECK(report["converged"] == true);
  const std::string stop = report["stop"];
  CHECK((stop == "relative change" || stop == "gradient norm" || stop == "stalled at floor"));
  CHECK_FALSE(report.contains("failure"));
}

TEST_CASE("flatten CLI: the same output bits with 1 and 2 threads (60K triangles)", "[flatten][cli]") {
  test::Scratch dir("flatten-threads");
  std::ofstream(dir / "big.obj") << grid_obj(175);  // 61,250 triangles: above the threading threshold
  // run_uvpress cannot set the environment; run through the shell for OMP_NUM_THREADS.
  auto run_with = [&](const char* threads) {
    std::string cmd = std::string("OMP_NUM_THREADS=") + threads + " OPENBLAS_NUM_THREADS=" + threads + " " +
                      UVPRESS_BINARY + " flatten " + quoted(dir / "big.obj") + " -o " +
                      quoted(dir / (std::string("t") + threads + ".obj")) + " --max-iter 6 >/dev/null 2>&1";
    return std::system(cmd.c_str());
  };
  REQUIRE(run_with("1") == 0);
  REQUIRE(run_with("2") == 0);
  const bool identical = test::read_file(dir / "t1.obj") == test::read_file(dir / "t2.obj");
  CHECK(identical);
}

// Real charts have holes (Fox 3 boundary loops, Duck 6, CesiumMilkTruck) or a non-manifold
// vertex (BoxTextured): holes are filled for the solve, a chart that still is no disk is
// skipped with a warning naming it, and the run exits 0 with zero flips.
TEST_CASE("flatten CLI: glTF charts with holes flatten, a chart that cannot is skipped and named", "[flatten][cli][shared]") {
  auto shared = test::shared_dir();
  if (!shared) UVPRESS_SKIP("no ../shared: the Fox, Duck, CesiumMilkTruck and BoxTextured glTFs are not here");
  test::Scratch dir("flatten-holes");
  for (const char* name : {"Fox", "Duck", "CesiumMilkTruck", "BoxTextured"}) {
    const auto input = *shared / "assets" / name / "glTF" / (std::string(name) + ".gltf");
    if (!test::fs::exists(input)) {
      WARN("skipped: " << input << " is not there");
      continue;
    }
    const auto out = dir / (std::string(name) + ".glb"), report = dir / (std::string(name) + ".json");
    auto r = run_uvpress("flatten " + quoted(input) + " -o " + quoted(out) + " --report " + quoted(report));
    INFO(name << "\nstdout: " << r.out << "\nstderr: " << r.err);
    REQUIRE(r.exit_code == 0);
    CHECK_THAT(r.out, Catch::Contains(" 0 flips") && Catch::Contains("new UV set TEXCOORD_"));
    CHECK_THAT(r.out, !Catch::Contains("eta") && !Catch::Contains("E_c"));  // solver jargon stays in --report
    // Whole-asset bytes before and after, as every command that writes an asset says them.
    CHECK_THAT(r.out, Catch::Matches(".*\\.gltf \\([0-9.]+ K?B\\): .* -> .*\\.glb \\([0-9.]+ K?B\\) \\(new UV set.*\n"));
    size_t skipped_lines = 0;
    for (const auto& line : r.err_lines()) {
      // Fox's own validator errors (strided animation and skin accessors): one line, kept.
      if (std::string(name) == "Fox" && line.find(": warning: 127 glTF validation errors") != std::string::npos) continue;
      CHECK_THAT(line, Catch::Matches(".*: warning: mesh [0-9]+ primitive [0-9]+ chart [0-9]+: skipped: .*"));
      ++skipped_lines;
    }
    auto j = nlohmann::json::parse(test::read_file(report));
    CHECK(j["flips"] == 0);
    CHECK(j["charts_skipped"].get<size_t>() == skipped_lines);
    CHECK(j["input_bytes"].get<uint64_t>() > 0);
    CHECK(j["output_bytes"].get<uint64_t>() > 0);
    CHECK(j["input_validation"]["errors"] == (std::string(name) == "Fox" ? 127 : 0));
    auto file = io::load_gltf(out.string());
    for (const auto& set : j["uv_sets_written"]) {
      size_t users = 0;
      for (const auto& mesh : file.model.meshes)
        for (const auto& prim : mesh.primitives) users += prim.attributes.count(set.get<std::string>());
      CHECK(users > 0);
    }
  }
}

TEST_CASE("flatten keeps an OBJ's materials and normals, and says that its UVs were replaced", "[flatten][cli]") {
  test::Scratch dir("flatten-obj-extras");
  // The bump grid with a material library, two materials, per-corner normals, old UVs and
  // a group line; faces written as quads split by the reader.
  const int n = 6;
  std::ostringstream obj;
  obj << "mtllib my materials.mtl\ng sheet\n";
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double x = double(i) / n, y = double(j) / n;
      obj << "v " << x << ' ' << y << ' ' << 0.3 * std::sin(3 * x) * y << "\nvt " << x << ' ' << y << '\n';
    }
  obj << "vn 0 0 1\nvn 0 0.6 0.8\n";
  for (int j = 0; j < n; ++j) {
    if (j == 0) obj << "usemtl red\n";
    if (j == n / 2) obj << "usemtl blue paint\n";
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i + 1, b = a + 1, c = a + n + 1, d = c + 1, vn = 1 + (i + j) % 2;
      obj << "f " << a << '/' << a << '/' << vn << ' ' << b << '/' << b << '/' << vn << ' ' << d << '/' << d << '/' << vn
          << ' ' << c << '/' << c << '/' << vn << '\n';
    }
  }
  std::ofstream(dir / "sheet.obj") << obj.str();
  io::ObjExtras in_extras;
  const Mesh in = io::read_mesh((dir / "sheet.obj").string(), &in_extras);
  REQUIRE(in_extras.normal_triangles.size() == in.triangles.size());

  auto r = run_uvpress("flatten " + quoted(dir / "sheet.obj") + " -o " + quoted(dir / "flat.obj"));
  INFO(r.out << r.err);
  REQUIRE(r.exit_code == 0);
  CHECK_THAT(r.out, Catch::Contains("the input's UVs (vt) replaced") && Catch::Contains("1 o/g/s lines not kept"));
  io::ObjExtras out_extras;
  const Mesh out = io::read_mesh((dir / "flat.obj").string(), &out_extras);
  CHECK(out.triangles == in.triangles);
  CHECK(out.uvs != in.uvs);  // new UVs
  CHECK(out_extras.mtllib == std::vector<std::string>{"my materials.mtl"});
  CHECK(out_extras.usemtl == in_extras.usemtl);
  REQUIRE(out_extras.usemtl.size() == 2);
  CHECK(out_extras.usemtl[1] == std::pair<size_t, std::string>{size_t(2 * n * n / 2), "blue paint"});
  CHECK(out_extras.normals == in_extras.normals);
  CHECK(out_extras.normal_triangles == in_extras.normal_triangles);
  // A mesh without any of it says nothing about it.
  std::ofstream(dir / "plain.obj") << grid_obj(6);
  r = run_uvpress("flatten " + quoted(dir / "plain.obj") + " -o " + quoted(dir / "plain-flat.obj"));
  REQUIRE(r.exit_code == 0);
  CHECK_THAT(r.out, !Catch::Contains("replaced") && !Catch::Contains("not kept"));
}

namespace {

// Per triangle: UV area over 3-D area, and their coefficient of variation (0: one density).
double density_spread(const std::vector<float>& positions, const std::vector<float>& uv, const std::vector<uint32_t>& idx) {
  std::vector<double> r;
  for (size_t t = 0; t + 2 < idx.size(); t += 3) {
    const float* a = &positions[3 * size_t(idx[t])];
    const float* b = &positions[3 * size_t(idx[t + 1])];
    const float* c = &positions[3 * size_t(idx[t + 2])];
    const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const double area = 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const float* p = &uv[2 * size_t(idx[t])];
    const float* q = &uv[2 * size_t(idx[t + 1])];
    const float* s = &uv[2 * size_t(idx[t + 2])];
    const double uv_area = 0.5 * std::abs(double(q[0] - p[0]) * (s[1] - p[1]) - double(s[0] - p[0]) * (q[1] - p[1]));
    if (area > 0) r.push_back(uv_area / area);
  }
  double mean = 0, var = 0;
  for (double x : r) mean += x / double(r.size());
  for (double x : r) var += (x - mean) * (x - mean) / double(r.size());
  return std::sqrt(var) / mean;
}

}  // namespace

// --assign: the materials sample the flattened UVs and the texture is re-baked into them. An
// asset whose UVs squeeze its left side 9x more than its right gets one texel density over
// its surface, and its texture still shows what it showed (scored on screen as written).
TEST_CASE("flatten --assign: the materials use the flattened UVs, the texture re-baked into them", "[flatten][cli][assign]") {
  test::Scratch dir("flatten-assign");
  io::GltfFile demo = pipeline::make_demo_asset({16, 256});
  auto& prim = demo.model.meshes[0].primitives[0];
  std::vector<float> uv = io::vertex_attribute(demo, 0, 0, "TEXCOORD_0", 2);
  for (size_t i = 0; i < uv.size(); i += 2) uv[i] = 0.2f * uv[i] + 0.8f * uv[i] * uv[i];  // du'/du from 0.2 to 1.8
  prim.attributes["TEXCOORD_0"] = io::append_float_accessor(demo.model, uv, TINYGLTF_TYPE_VEC2);
  const auto in = dir / "squeezed.glb", out = dir / "flat.glb", report = dir / "flat.json";
  io::save_gltf(demo, in.string());
  const std::vector<float> positions = io::vertex_attribute(demo, 0, 0, "POSITION", 3);
  const io::Asset before = io::build_asset(demo);
  const double spread_in = density_spread(positions, uv, before.primitives[0].indices);

  auto r = run_uvpress("flatten " + quoted(in) + " -o " + quoted(out) + " --assign --device cpu --report " + quoted(report));
  INFO("stdout: " << r.out << "\nstderr: " << r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(r.err.empty());
  CHECK_THAT(r.out, Catch::Contains("1 charts flattened") && Catch::Contains("re-baked into TEXCOORD_0") &&
                        Catch::Contains("on screen q"));
  CHECK(test::validate_gltf(out)["numErrors"] == 0);
  const auto j = nlohmann::json::parse(test::read_file(report));
  CHECK(j["flips"] == 0);
  CHECK(j["overlaps_new"] == 0);
  CHECK(j["layouts"][0]["isometric"]["charts_flattened"] == 1);
  CHECK(j["cost_ratio"].get<double>() == Approx(1.0).margin(0.02));

  // The material's texCoord set is the flattened one: one density where the input had a
  // 9:1 squeeze, and the image was re-baked (a repointed texture would scramble it: q > 0.05).
  const io::GltfFile result = io::load_gltf(out.string());
  const io::Asset after = io::build_asset(result);
  const int tex_coord = result.model.materials[0].pbrMetallicRoughness.baseColorTexture.texCoord;
  const std::vector<float> new_uv = io::vertex_attribute(result, 0, 0, "TEXCOORD_" + std::to_string(tex_coord), 2);
  const double spread_out = density_spread(io::vertex_attribute(result, 0, 0, "POSITION", 3), new_uv, after.primitives[0].indices);
  CHECK(spread_in > 0.3);
  CHECK(spread_out < 0.2 * spread_in);
  CHECK(result.image_bytes[0] != demo.image_bytes[0]);
  // Evening the density out moves texels from the over-sampled right to the under-sampled
  // left: the right loses detail the input had, and q says so (not a re-bake error: below).
  CHECK(j["q"].get<double>() > 0);

  // The sheet as generated (UVs already near one density): flattened, turned back to its
  // input orientation and packed, its charts hold a share of the image's texels, and the
  // re-bake loses no more than the plain resize of the input to that share (eval's input
  // curve there; 0.0136 against 0.0139 at 512^2). A texture left in the old layout, or
  // re-baked through the wrong triangles, scores several times that.
  const auto plain = dir / "plain.glb", plain_out = dir / "plain-flat.glb", plain_report = dir / "plain-flat.json";
  io::save_gltf(pipeline::make_demo_asset({16, 256}), plain.string());
  r = run_uvpress("flatten " + quoted(plain) + " -o " + quoted(plain_out) + " --assign --device cpu --report " + quoted(plain_report));
  REQUIRE(r.exit_code == 0);
  const auto jp = nlohmann::json::parse(test::read_file(plain_report));
  const double share = jp["layouts"][0]["chart_cost_ratio"].get<double>();
  CHECK(share > 0.85);  // turned back to the input's orientation, the sheet fills its box
  char grid[32];
  std::snprintf(grid, sizeof grid, "%.4f", share);
  r = run_uvpress("eval " + quoted(plain) + " --cost-grid " + grid + " --device cpu --report " + quoted(dir / "eval.json"));
  REQUIRE(r.exit_code == 0);
  const double q_resize = nlohmann::json::parse(test::read_file(dir / "eval.json"))["layouts"][0]["curve"][0]["q"].get<double>();
  INFO("q flattened " << jp["q"].get<double>() << ", q resized to " << share << " of the texels " << q_resize);
  CHECK(jp["q"].get<double>() < 1.25 * q_resize);
}

TEST_CASE("flatten --assign on Duck: charts that share texels get their own, the file stays valid", "[flatten][cli][assign][shared]") {
  auto shared = test::shared_dir();
  if (!shared) UVPRESS_SKIP("no ../shared: Duck is not here");
  test::Scratch dir("flatten-assign-duck");
  const auto in = *shared / "assets" / "Duck" / "glTF-Binary" / "Duck.glb", out = dir / "duck.glb", report = dir / "duck.json";
  auto r = run_uvpress("flatten " + quoted(in) + " -o " + quoted(out) + " --assign --device cpu --report " + quoted(report));
  INFO("stdout: " << r.out << "\nstderr: " << r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(test::validate_gltf(out)["numErrors"] == 0);
  const auto j = nlohmann::json::parse(test::read_file(report));
  const auto& iso = j["layouts"][0]["isometric"];
  // Duck's mirrored halves share texels; flattened, each has its own.
  CHECK(j["layouts"][0]["shared_texel_charts"].get<size_t>() > 0);
  CHECK(iso["charts_flattened"].get<size_t>() + iso["charts_kept"].get<size_t>() == j["layouts"][0]["charts"].get<size_t>());
  CHECK(iso["charts_flattened"].get<size_t>() >= j["layouts"][0]["shared_texel_charts"].get<size_t>());
  // Every chart kept is named, with its reason, in a warning (progress lines, which a slow
  // machine prints for stages past 5 s, are not counted).
  size_t warnings = 0;
  for (const auto& line : r.err_lines()) warnings += line.find(": warning: ") != std::string::npos;
  CHECK(warnings == iso["charts_kept"].get<size_t>());
  CHECK(j["flips"] == 0);
  CHECK(j["overlaps_new"] == 0);
  CHECK(j["q"].is_number());
}

TEST_CASE("flatten --assign refuses what it cannot do, before any work", "[flatten][cli][assign]") {
  test::Scratch dir("flatten-assign-errors");
  std::ofstream(dir / "grid.obj") << grid_obj(4);
  test::Scratch out("flatten-assign-errors-out");
  test::check_input_error(out, "flatten " + quoted(dir / "grid.obj") + " -o " + quoted(out / "x.obj") + " --assign",
                          dir / "grid.obj", "--assign needs a glTF input");
  io::save_gltf(pipeline::make_demo_asset({4, 32}), (dir / "demo.glb").string());
  test::check_input_error(out, "flatten " + quoted(dir / "demo.glb") + " -o " + quoted(out / "x.glb") + " --assign --log " + quoted(out / "l.csv"),
                          out / "l.csv", "--log is not written with --assign");
  // Nothing textured: nothing to assign the UVs to.
  io::GltfFile plain = pipeline::make_demo_asset({4, 32});
  plain.model.materials[0].pbrMetallicRoughness.baseColorTexture = tinygltf::TextureInfo();
  io::save_gltf(plain, (dir / "untextured.glb").string());
  test::check_input_error(out, "flatten " + quoted(dir / "untextured.glb") + " -o " + quoted(out / "x.glb") + " --assign --device cpu",
                          dir / "untextured.glb", "--assign: no textured layout to flatten");
}
