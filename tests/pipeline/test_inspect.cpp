// `info` figures against what is known of the Khronos sample models.
#include <catch2/catch.hpp>

#include "io/gltf_io.h"
#include "pipeline/inspect.h"
#include "support.h"

#include <set>

using namespace uvpress;

namespace {

nlohmann::ordered_json info_of(const std::string& relative) {
  return pipeline::inspect(io::load_gltf((*test::shared_dir() / "assets" / relative).string()));
}

}  // namespace

TEST_CASE("info: Duck has 4,212 triangles and one 512x512 baseColor", "[pipeline][info][shared]") {
  if (!test::shared_dir()) UVPRESS_SKIP("../shared is absent");
  for (const char* file : {"Duck/glTF-Binary/Duck.glb", "Duck/glTF/Duck.gltf"}) {
    INFO(file);
    auto info = info_of(file);
    CHECK(info["triangles"] == 4212);
    REQUIRE(info["images"].size() == 1);
    const auto& img = info["images"][0];
    CHECK(img["width"] == 512);
    CHECK(img["height"] == 512);
    CHECK(img["color_space"] == "sRGB");
    REQUIRE(img["uses"].size() == 1);
    CHECK(img["uses"][0]["role"] == "baseColor");
    CHECK(img["uses"][0]["tex_coord"] == 0);
    CHECK(info["primitives"][0]["uv_sets"].size() == 1);
    CHECK(info["tiled"] == false);
  }
}

TEST_CASE("info: CesiumMilkTruck's atlas is sampled by two materials", "[pipeline][info][shared]") {
  if (!test::shared_dir()) UVPRESS_SKIP("../shared is absent");
  auto info = info_of("CesiumMilkTruck/glTF/CesiumMilkTruck.gltf");
  CHECK(info["triangles"] == 2856);
  REQUIRE(info["images"].size() == 1);
  CHECK(info["images"][0]["width"] == 2048);
  CHECK(info["images"][0]["materials"].size() == 2);
  CHECK(info["counts"]["animations"] == 1);
}

TEST_CASE("info: BoxTextured is tiled", "[pipeline][info][shared]") {
  if (!test::shared_dir()) UVPRESS_SKIP("../shared is absent");
  for (const char* file : {"BoxTextured/glTF/BoxTextured.gltf", "BoxTextured/glTF-Embedded/BoxTextured.gltf"}) {
    auto info = info_of(file);
    CHECK(info["tiled"] == true);
    CHECK(info["images"][0]["uses"][0]["tiled"] == true);
    CHECK(info["primitives"][0]["uv_sets"][0]["max"][0].get<double>() > 1.5);
  }
}

TEST_CASE("info: MultiUVTest's emissive uses TEXCOORD_1", "[pipeline][info][shared]") {
  if (!test::shared_dir()) UVPRESS_SKIP("../shared is absent");
  auto info = info_of("MultiUVTest/glTF/MultiUVTest.gltf");
  bool found = false;
  for (const auto& img : info["images"])
    for (const auto& use : img["uses"])
      if (use["role"] == "emissive") {
        found = true;
        CHECK(use["tex_coord"] == 1);
      }
  CHECK(found);
  CHECK(info["primitives"][0]["uv_sets"].size() == 2);
}

TEST_CASE("info: TextureTransformTest reads KHR_texture_transform and clamps, not tiles", "[pipeline][info][shared]") {
  if (!test::shared_dir()) UVPRESS_SKIP("../shared is absent");
  auto info = info_of("TextureTransformTest/glTF/TextureTransformTest.gltf");
  int transformed = 0;
  for (const auto& img : info["images"])
    for (const auto& use : img["uses"]) transformed += use.contains("transform");
  CHECK(transformed == 6);
  CHECK(info["images"][0]["uses"].size() == 3);  // one image under three transforms
  CHECK(info["tiled"] == false);
}

TEST_CASE("info: Fox keeps its skin and three animations", "[pipeline][info][shared]") {
  if (!test::shared_dir()) UVPRESS_SKIP("../shared is absent");
  auto info = info_of("Fox/glTF/Fox.gltf");
  CHECK(info["triangles"] == 576);
  CHECK(info["counts"]["skins"] == 1);
  CHECK(info["counts"]["animations"] == 3);
}

TEST_CASE("info: one numbering of primitives, glTF's mesh.primitive, in every section", "[pipeline][info][shared]") {
  if (!test::shared_dir()) UVPRESS_SKIP("../shared is absent");
  // The truck's wheels are mesh 1's primitive 0, the fourth primitive in file order: the
  // image section said "primitive 3" where the primitive section says "1.0".
  const auto info = info_of("CesiumMilkTruck/glTF/CesiumMilkTruck.gltf");
  std::set<std::pair<int, int>> listed;
  for (const auto& p : info["primitives"]) listed.insert({p["mesh"].get<int>(), p["primitive"].get<int>()});
  REQUIRE(info["images"].size() == 1);
  std::set<std::pair<int, int>> used;
  for (const auto& u : info["images"][0]["uses"]) {
    const std::pair<int, int> key = {u["mesh"].get<int>(), u["primitive"].get<int>()};
    CHECK(listed.count(key) == 1);
    used.insert(key);
  }
  CHECK(used == std::set<std::pair<int, int>>{{0, 0}, {1, 0}});
  const std::string text = pipeline::format_inspection(info);
  CHECK(text.find("on primitive 1.0 via TEXCOORD_0") != std::string::npos);
  CHECK(text.find("on primitive 3 ") == std::string::npos);
}
