// `--texture-format astc` as a user runs it (issue 18, item 4): reparam aligns charts to the
// ASTC block, writes KTX2 copies the validator accepts and loads its own output again; copy
// on the shared assets adds no validator code the input did not have.
#include <catch2/catch.hpp>

#include "io/astc_codec.h"
#include "io/atomic_file.h"
#include "io/gltf_io.h"
#include "io/ktx2.h"
#include "pipeline/demo_asset.h"
#include "support.h"

#include <fstream>
#include <string>

using namespace uvpress;
namespace fs = std::filesystem;

namespace {

using test::quoted;

}  // namespace

TEST_CASE("CLI: reparam --texture-format astc aligns charts to the block, writes KTX2 copies, and loads its own output",
          "[cli][ktx2]") {
  test::Scratch dir("ktx2-cli");
  io::save_gltf(pipeline::make_demo_asset({12, 128}), (dir / "demo.glb").string());
  auto r = test::run_uvpress("reparam " + quoted(dir / "demo.glb") + " -o " + quoted(dir / "out.gltf") +
                             " --cost 0.5 --no-optimize --texture-format astc --astc-block 8x8 --astc-quality fast --report " +
                             quoted(dir / "r.json"));
  INFO(r.out << r.err);
  REQUIRE(r.exit_code == 0);
  CHECK_THAT(r.out, Catch::Contains("KTX2 (ASTC 8x8, fast)"));
  std::ifstream in(dir / "r.json");
  const auto report = nlohmann::json::parse(in);
  REQUIRE(report["gpu_textures"].size() == 1);
  const auto& t = report["gpu_textures"][0];
  CHECK(t["vk_format"] == io::astc_vk_format(8, 8, true));
  CHECK(t["psnr_db"].get<double>() > 20);
  // --astc-block 8x8 set --block-align 8: the atlas is whole blocks.
  CHECK(report["textures"][0]["new_size"][0].get<uint32_t>() % 8 == 0);
  CHECK(report["textures"][0]["new_size"][1].get<uint32_t>() % 8 == 0);
  CHECK(t["size"] == report["textures"][0]["new_size"]);
  CHECK(test::validate_gltf(dir / "out.gltf")["numErrors"] == 0);

  // reparam of its own ASTC output: loads (the KTX2 copy is read and checked), re-bakes,
  // writes a fresh copy for the new image.
  auto r2 = test::run_uvpress("reparam " + quoted(dir / "out.gltf") + " -o " + quoted(dir / "again.gltf") +
                              " --cost 0.8 --no-optimize --texture-format astc --astc-block 8x8 --astc-quality fast");
  INFO(r2.out << r2.err);
  REQUIRE(r2.exit_code == 0);
  std::ifstream in2(dir / "again.gltf");
  const auto json = nlohmann::json::parse(in2);
  const fs::path ktx2 = dir / json["images"][0]["extras"]["uvpress_ktx2"]["uri"].get<std::string>();
  REQUIRE(fs::exists(ktx2));
  const auto info = io::read_ktx2(io::read_file(ktx2.string()), ktx2.string());
  CHECK(info.block_x == 8);
  CHECK(test::validate_gltf(dir / "again.gltf")["numErrors"] == 0);
}

TEST_CASE("CLI: copy --texture-format astc on the shared assets validates with nothing new", "[cli][ktx2][shared]") {
  auto shared = test::shared_dir();
  if (!shared) UVPRESS_SKIP("../shared is absent");
  test::Scratch dir("ktx2-shared");
  for (const char* rel : {"Duck/glTF-Binary/Duck.glb", "BoxTextured/glTF/BoxTextured.gltf"}) {
    const fs::path asset = *shared / "assets" / rel;
    const fs::path out = dir / (asset.stem().string() + ".gltf");
    auto r = test::run_uvpress("copy " + quoted(asset) + " -o " + quoted(out) + " --texture-format astc --astc-quality fastest");
    INFO(rel << ": " << r.out << r.err);
    REQUIRE(r.exit_code == 0);
    const auto v_in = test::validate_gltf(asset), v_out = test::validate_gltf(out);
    CHECK(v_out["numErrors"] == 0);
    CHECK(v_out["codes"] == v_in["codes"]);
  }
}
