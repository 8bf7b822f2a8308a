// Pruning what a replacement leaves behind (issue 18): replaced UV accessors, their
// bufferViews and old image bytes go; what the input itself left unused stays; the
// validator sees no new UNUSED_OBJECT; references are renumbered correctly.
#include <catch2/catch.hpp>

#include "io/asset.h"
#include "io/gltf_append.h"
#include "io/gltf_io.h"
#include "io/gltf_prune.h"
#include "io/image_io.h"
#include "pipeline/demo_asset.h"
#include "support.h"

using namespace uvpress;
namespace fs = std::filesystem;

namespace {

int unused_objects(const nlohmann::json& validation) { return validation["codes"].value("UNUSED_OBJECT", 0); }

}  // namespace

TEST_CASE("prune: a replaced UV accessor, its bufferView and replaced image bytes go, the input's own unused accessor stays",
          "[io][prune]") {
  test::Scratch dir("prune");
  // The demo asset with one accessor nothing references (the input's, not ours to drop),
  // saved as .glb so that its image lives in a bufferView.
  io::GltfFile demo = pipeline::make_demo_asset({8, 64});
  const int planted = io::append_float_accessor(demo.model, {0.f, 0.f, 1.f, 1.f}, TINYGLTF_TYPE_VEC2);
  io::save_gltf(demo, (dir / "in.glb").string());
  const io::GltfFile in = io::load_gltf((dir / "in.glb").string());
  const auto in_validation = test::validate_gltf(dir / "in.glb");
  REQUIRE(unused_objects(in_validation) >= 1);  // the planted accessor (and its bufferView)

  // What reparam does: a new TEXCOORD_0 appended (the old accessor is left), new image bytes.
  io::GltfFile out = in;
  const io::Asset asset = io::build_asset(in);
  std::vector<float> uv = asset.primitives[0].uv_sets[0].uv;
  for (float& v : uv) v = 0.25f + 0.5f * v;
  auto& prim = out.model.meshes[0].primitives[0];
  const int old_uv = prim.attributes["TEXCOORD_0"];
  prim.attributes["TEXCOORD_0"] = io::append_float_accessor(out.model, uv, TINYGLTF_TYPE_VEC2);
  Image small = io::decode_image(in.image_bytes[0], "in");
  small.width = small.height = 16;
  small.pixels.resize(16 * 16 * small.channels, 0.5f);
  out.image_bytes[0] = io::encode_image(small, "png");

  // Without pruning the file keeps the old UVs and image bytes.
  io::save_gltf(out, (dir / "unpruned.glb").string());
  const auto unpruned = test::validate_gltf(dir / "unpruned.glb");
  CHECK(unused_objects(unpruned) > unused_objects(in_validation));

  const io::PruneResult r = io::prune_replaced(out, in.model);
  CHECK(r.skipped.empty());
  CHECK(r.accessors == 1);     // the old TEXCOORD_0
  CHECK(r.buffer_views == 2);  // its view and the old image's
  CHECK(out.model.accessors.size() == in.model.accessors.size());
  CHECK(out.model.bufferViews.size() == in.model.bufferViews.size() - 1);  // the new image's view comes on save
  io::save_gltf(out, (dir / "out.glb").string());
  const auto validation = test::validate_gltf(dir / "out.glb");
  CHECK(validation["numErrors"] == 0);
  CHECK(unused_objects(validation) == unused_objects(in_validation));

  // What it reads back is what was written: the new UVs and image, the rest unchanged.
  const io::GltfFile back = io::load_gltf((dir / "out.glb").string());
  const io::Asset b = io::build_asset(back);
  CHECK(b.primitives[0].uv_sets[0].uv == uv);
  CHECK(b.primitives[0].positions == asset.primitives[0].positions);
  CHECK(b.primitives[0].indices == asset.primitives[0].indices);
  CHECK(back.image_bytes[0] == out.image_bytes[0]);
  // The planted accessor is still there, with its values (renumbered past the old UVs).
  const int planted_now = planted > old_uv ? planted - 1 : planted;
  const auto& a = back.model.accessors[size_t(planted_now)];
  CHECK(a.count == 2);
  CHECK(a.maxValues == std::vector<double>{1.0, 1.0});
  // Smaller than the unpruned file by at least the old image and UV bytes.
  CHECK(fs::file_size(dir / "out.glb") + in.image_bytes[0].size() + 4 * uv.size() <= fs::file_size(dir / "unpruned.glb") + 64);
}

TEST_CASE("prune: nothing replaced, nothing removed", "[io][prune]") {
  io::GltfFile demo = pipeline::make_demo_asset({8, 64});
  io::append_float_accessor(demo.model, {0.f, 0.f}, TINYGLTF_TYPE_VEC2);  // unused in the input: kept
  const io::GltfFile in = demo;
  const io::PruneResult r = io::prune_replaced(demo, in.model);
  CHECK(r.accessors == 0);
  CHECK(r.buffer_views == 0);
  CHECK(demo.model.accessors.size() == in.model.accessors.size());
  CHECK(demo.model.buffers[0].data == in.model.buffers[0].data);
}
