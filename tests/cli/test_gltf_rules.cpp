// The glTF rules checked on load (io/gltf_rules.h) as a user meets them: an input that
// breaks them is one warning line and a count in the report, a valid one none, and --strict
// refuses the broken one as an input error.
#include "support.h"

#include "io/gltf_io.h"
#include "pipeline/demo_asset.h"

#include <catch2/catch.hpp>

#include <fstream>

using namespace uvpress;
namespace fs = std::filesystem;

TEST_CASE("An input that breaks the rules is one warning, or refused under --strict", "[io][gltf][rules][cli]") {
  test::Scratch dir("gltf_rules_cli");
  io::GltfFile file = pipeline::make_demo_asset({8, 32});
  const tinygltf::Primitive prim = file.model.meshes[0].primitives[0];
  file.model.accessors[size_t(prim.attributes.at("TEXCOORD_0"))].maxValues = {1.5, 1.5};  // above every value
  const fs::path in = dir / "in.gltf";
  io::save_gltf(file, in.string());

  const auto r = test::run_uvpress("copy " + in.string() + " -o " + (dir / "out.glb").string() + " --report " +
                                   (dir / "out.json").string());
  REQUIRE(r.exit_code == 0);
  const auto lines = r.err_lines();
  REQUIRE(lines.size() == 1);
  CHECK(lines[0].find(in.string() + ": warning: 2 glTF validation errors") != std::string::npos);
  CHECK(lines[0].find("ACCESSOR_MAX_MISMATCH") != std::string::npos);
  std::ifstream report((dir / "out.json").string());
  const nlohmann::json j = nlohmann::json::parse(report);
  CHECK(j["input_validation"]["errors"] == 2);
  CHECK(j["input_validation"]["codes"]["ACCESSOR_MAX_MISMATCH"] == 2);

  // A valid input: no warning, zero errors in the report.
  const fs::path ok = dir / "ok.gltf";
  io::save_gltf(pipeline::make_demo_asset({8, 32}), ok.string());
  const auto clean = test::run_uvpress("--strict copy " + ok.string() + " -o " + (dir / "ok.glb").string());
  CHECK(clean.exit_code == 0);
  CHECK(clean.err.empty());

  test::Scratch out("gltf_rules_strict");
  test::check_input_error(out, "--strict copy " + in.string() + " -o " + (out / "x.glb").string(), in,
                          "2 glTF validation errors (2 ACCESSOR_MAX_MISMATCH): refused (--strict)");
}
