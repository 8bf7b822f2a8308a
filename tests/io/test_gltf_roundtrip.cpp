// Every shared asset survives load -> save (.gltf and .glb) -> load: the Khronos validator
// finds no error the input did not have, images decode to identical pixels, and what
// uvpress did not touch is still there.
#include <catch2/catch.hpp>

#include "core/error.h"
#include "io/gltf_io.h"
#include "io/image_io.h"
#include "support.h"

#include <fstream>

using namespace uvpress;

namespace {

std::vector<std::string> names_of(const std::vector<tinygltf::Node>& v) {
  std::vector<std::string> n;
  for (auto& x : v) n.push_back(x.name);
  return n;
}

std::vector<std::string> names_of(const std::vector<tinygltf::Material>& v) {
  std::vector<std::string> n;
  for (auto& x : v) n.push_back(x.name);
  return n;
}

void check_same_content(const io::GltfFile& in, const io::GltfFile& out) {
  const auto &a = in.model, &b = out.model;
  CHECK(a.nodes.size() == b.nodes.size());
  CHECK(a.meshes.size() == b.meshes.size());
  CHECK(a.materials.size() == b.materials.size());
  CHECK(a.animations.size() == b.animations.size());
  CHECK(a.skins.size() == b.skins.size());
  CHECK(a.textures.size() == b.textures.size());
  CHECK(a.samplers.size() == b.samplers.size());
  CHECK(a.accessors.size() == b.accessors.size());
  CHECK(a.scenes.size() == b.scenes.size());
  CHECK(names_of(a.nodes) == names_of(b.nodes));
  CHECK(names_of(a.materials) == names_of(b.materials));
  CHECK(a.extensionsUsed == b.extensionsUsed);
  CHECK(a.extensionsRequired == b.extensionsRequired);
  for (size_t i = 0; i < std::min(a.meshes.size(), b.meshes.size()); ++i)
    CHECK(a.meshes[i].primitives.size() == b.meshes[i].primitives.size());
  for (size_t i = 0; i < std::min(a.materials.size(), b.materials.size()); ++i)
    CHECK(a.materials[i].extensions.size() == b.materials[i].extensions.size());
  REQUIRE(in.image_bytes.size() == out.image_bytes.size());
  for (size_t i = 0; i < in.image_bytes.size(); ++i) {
    Image x = io::decode_image(in.image_bytes[i], "in"), y = io::decode_image(out.image_bytes[i], "out");
    CHECK(x.width == y.width);
    CHECK(x.height == y.height);
    CHECK(x.channels == y.channels);
    CHECK(x.pixels == y.pixels);
  }
}

// No error code appears more often in `out` than in `in`.
void check_no_new_errors(const nlohmann::json& in, const nlohmann::json& out) {
  for (auto& [code, count] : out["errors"].items()) {
    INFO("validator error " << code);
    CHECK(count.get<int>() <= in["errors"].value(code, 0));
  }
  CHECK(out["numErrors"].get<int>() <= in["numErrors"].get<int>());
}

}  // namespace

TEST_CASE("Every shared asset round-trips as .gltf and .glb", "[io][gltf][shared]") {
  auto assets = test::shared_assets();
  if (assets.empty()) UVPRESS_SKIP("../shared/assets is absent");
  for (const auto& path : assets) {
    INFO(path.string());
    io::GltfFile in = io::load_gltf(path.string());
    auto in_report = test::validate_gltf(path);
    test::Scratch dir("roundtrip");
    for (const char* ext : {".glb", ".gltf"}) {
      INFO(ext);
      auto out_path = dir / (path.stem().string() + ext);
      io::save_gltf(in, out_path.string());
      check_no_new_errors(in_report, test::validate_gltf(out_path));
      check_same_content(in, io::load_gltf(out_path.string()));
    }
    // No temporaries left behind.
    for (auto& f : dir.files()) CHECK(f.find(".tmp-") == std::string::npos);
  }
}

TEST_CASE("Malformed glTF gives InputError with a one-line reason", "[io][gltf]") {
  test::Scratch dir("badgltf");
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name, std::ios::binary) << text;
    return (dir / name).string();
  };
  auto reason = [](const std::string& path) {
    try {
      io::load_gltf(path);
    } catch (const InputError& e) {
      CHECK(e.file() == path);
      CHECK(std::string(e.what()).find('\n') == std::string::npos);
      return std::string(e.what());
    }
    FAIL("no InputError for " << path);
    return std::string();
  };
  CHECK_THAT(reason((dir / "missing.gltf").string()), Catch::Contains("not found"));
  CHECK_THAT(reason(write("empty.gltf", "")), Catch::Contains("empty"));
  CHECK_FALSE(reason(write("bad.gltf", "{\"asset\": {\"version\": \"2.0\"")).empty());
  CHECK_THAT(reason(write("magic.glb", "glTX\x02\0\0\0")), Catch::Contains("magic"));
  CHECK_THAT(reason(write("short.glb", std::string("glTF\x02\0\0\0", 8))), Catch::Contains("truncated"));
  CHECK_THAT(reason(write("ext.gltf", R"({"asset":{"version":"2.0"},"extensionsUsed":["FOO_bar"],"extensionsRequired":["FOO_bar"]})")),
             Catch::Contains("FOO_bar"));
  CHECK_THAT(reason(write("noimg.gltf", R"({"asset":{"version":"2.0"},"images":[{"uri":"nothere.png"}]})")),
             Catch::Contains("nothere.png"));
  CHECK_THAT(reason(write("v1.gltf", R"({"asset":{"version":"1.0"}})")), Catch::Contains("version"));
}

TEST_CASE("save_gltf refuses other extensions and writes nothing", "[io][gltf]") {
  test::Scratch dir("badext");
  io::GltfFile f;
  f.model.asset.version = "2.0";
  CHECK_THROWS_AS(io::save_gltf(f, (dir / "out.obj").string()), InputError);
  CHECK(dir.files().empty());
  CHECK_THROWS_AS(io::save_gltf(f, (dir / "no/such/dir/out.glb").string()), InputError);
  CHECK(dir.files().empty());
}
