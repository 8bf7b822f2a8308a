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

#include <cstring>

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

namespace {

// The bytes of accessor `a` (tightly packed elements, as the tests here write them).
std::vector<uint8_t> accessor_bytes(const tinygltf::Model& m, int a) {
  const auto& acc = m.accessors[size_t(a)];
  const auto& view = m.bufferViews[size_t(acc.bufferView)];
  const size_t element = size_t(tinygltf::GetComponentSizeInBytes(uint32_t(acc.componentType))) *
                         size_t(tinygltf::GetNumComponentsInType(uint32_t(acc.type)));
  const size_t stride = view.byteStride ? view.byteStride : element;
  std::vector<uint8_t> out;
  const auto& data = m.buffers[size_t(view.buffer)].data;
  for (size_t i = 0; i < acc.count; ++i) {
    const size_t at = view.byteOffset + acc.byteOffset + i * stride;
    out.insert(out.end(), data.begin() + long(at), data.begin() + long(at + element));
  }
  return out;
}

}  // namespace

TEST_CASE("prune: a replaced UV accessor's bytes leave the bufferView it shared with attributes still used",
          "[io][prune]") {
  // Fox keeps TEXCOORD_0 and JOINTS_0 in one bufferView; here the replaced UVs sit between
  // two attributes that stay, so the view loses its middle and the second one moves.
  test::Scratch dir("prune-shared");
  io::GltfFile demo = pipeline::make_demo_asset({8, 64});
  auto& p0 = demo.model.meshes[0].primitives[0];
  const int uv0 = p0.attributes["TEXCOORD_0"];
  const std::vector<uint8_t> uv_bytes = accessor_bytes(demo.model, uv0);
  const size_t n = demo.model.accessors[size_t(uv0)].count, len = 8 * n;
  std::vector<uint8_t> shared(3 * len);
  std::vector<float> first(2 * n), last(2 * n);
  for (size_t i = 0; i < 2 * n; ++i) first[i] = 0.001f * float(i), last[i] = 1.0f - 0.002f * float(i % 300);
  std::memcpy(shared.data(), first.data(), len);
  std::memcpy(shared.data() + len, uv_bytes.data(), len);
  std::memcpy(shared.data() + 2 * len, last.data(), len);
  const int view = io::append_buffer_view(demo.model, shared.data(), shared.size(), TINYGLTF_TARGET_ARRAY_BUFFER);
  demo.model.bufferViews[size_t(view)].byteStride = 8;
  auto add = [&](size_t offset) {
    tinygltf::Accessor a = demo.model.accessors[size_t(uv0)];
    a.bufferView = view, a.byteOffset = offset;
    demo.model.accessors.push_back(a);
    return int(demo.model.accessors.size() - 1);
  };
  const int a1 = add(0), a0 = add(len), a2 = add(2 * len);
  demo.model.accessors[size_t(a1)].minValues = {first[0], first[1]}, demo.model.accessors[size_t(a1)].maxValues = {first[2 * n - 2], first[2 * n - 1]};
  demo.model.accessors[size_t(a2)].minValues.clear(), demo.model.accessors[size_t(a2)].maxValues.clear();
  p0.attributes["TEXCOORD_0"] = a0;
  p0.attributes["TEXCOORD_1"] = a1;
  p0.attributes["TEXCOORD_2"] = a2;
  // The demo's own UV accessor is now unused in the input: the input's, kept.
  io::save_gltf(demo, (dir / "in.gltf").string());
  const io::GltfFile in = io::load_gltf((dir / "in.gltf").string());
  const auto in_validation = test::validate_gltf(dir / "in.gltf");
  INFO(in_validation.dump());
  REQUIRE(in_validation["numErrors"] == 0);

  io::GltfFile out = in;
  std::vector<float> uv(2 * n);
  std::memcpy(uv.data(), uv_bytes.data(), len);
  for (float& v : uv) v = 0.25f + 0.5f * v;
  out.model.meshes[0].primitives[0].attributes["TEXCOORD_0"] = io::append_float_accessor(out.model, uv, TINYGLTF_TYPE_VEC2);
  const size_t appended = out.model.buffers[0].data.size() - in.model.buffers[0].data.size();
  const io::PruneResult r = io::prune_replaced(out, in.model);
  CHECK(r.skipped.empty());
  CHECK(r.accessors == 1);
  CHECK(r.buffer_views == 0);   // the shared view stays, smaller
  CHECK(r.buffer_bytes == len);  // exactly the old UVs (a multiple of 4: no padding)
  CHECK(out.model.buffers[0].data.size() == in.model.buffers[0].data.size() + appended - len);
  io::save_gltf(out, (dir / "out.gltf").string());
  const auto validation = test::validate_gltf(dir / "out.gltf");
  CHECK(validation["numErrors"] == 0);
  CHECK(unused_objects(validation) == unused_objects(in_validation));

  const io::GltfFile back = io::load_gltf((dir / "out.gltf").string());
  const auto& p = back.model.meshes[0].primitives[0];
  const int b1 = p.attributes.at("TEXCOORD_1"), b2 = p.attributes.at("TEXCOORD_2");
  CHECK(back.model.accessors[size_t(b1)].bufferView == back.model.accessors[size_t(b2)].bufferView);
  CHECK(back.model.bufferViews[size_t(back.model.accessors[size_t(b1)].bufferView)].byteLength == 2 * len);
  std::vector<uint8_t> want1(len), want2(len);
  std::memcpy(want1.data(), first.data(), len);
  std::memcpy(want2.data(), last.data(), len);
  CHECK(accessor_bytes(back.model, b1) == want1);
  CHECK(accessor_bytes(back.model, b2) == want2);
  CHECK(io::build_asset(back).primitives[0].uv_sets[0].uv == uv);
}

TEST_CASE("prune: Fox's replaced UVs leave its file no larger than the input", "[io][prune][shared]") {
  auto shared = test::shared_dir();
  if (!shared) UVPRESS_SKIP("../shared is absent");
  const fs::path fox = *shared / "assets/Fox/glTF/Fox.gltf";
  if (!fs::exists(fox)) UVPRESS_SKIP("../shared/assets/Fox is absent");
  const io::GltfFile in = io::load_gltf(fox.string());
  io::GltfFile out = in;
  auto& prim = out.model.meshes[0].primitives[0];
  const int old_uv = prim.attributes.at("TEXCOORD_0");
  const int joints = prim.attributes.at("JOINTS_0");
  // The input shares one bufferView between TEXCOORD_0 and JOINTS_0 (what this case is about).
  REQUIRE(in.model.accessors[size_t(old_uv)].bufferView == in.model.accessors[size_t(joints)].bufferView);
  const std::vector<uint8_t> joint_bytes = accessor_bytes(in.model, joints);
  const io::Asset asset = io::build_asset(in);
  std::vector<float> uv = asset.primitives[0].uv_sets[0].uv;
  for (float& v : uv) v = 0.5f * v;
  prim.attributes["TEXCOORD_0"] = io::append_float_accessor(out.model, uv, TINYGLTF_TYPE_VEC2);
  const io::PruneResult r = io::prune_replaced(out, in.model);
  CHECK(r.accessors == 1);
  CHECK(r.buffer_bytes == 8 * uv.size() / 2);
  // The new UVs take exactly the old ones' bytes: the buffer is the input's size.
  CHECK(out.model.buffers[0].data.size() == in.model.buffers[0].data.size());
  test::Scratch dir("prune-fox");
  io::save_gltf(out, (dir / "Fox.gltf").string());
  const io::GltfFile back = io::load_gltf((dir / "Fox.gltf").string());
  const auto& p = back.model.meshes[0].primitives[0];
  CHECK(accessor_bytes(back.model, p.attributes.at("JOINTS_0")) == joint_bytes);
  CHECK(io::build_asset(back).primitives[0].uv_sets[0].uv == uv);
  const auto before = test::validate_gltf(fox), after = test::validate_gltf(dir / "Fox.gltf");
  CHECK(after["numErrors"] == before["numErrors"]);
  CHECK(unused_objects(after) == unused_objects(before));
}
