#include "batch/corpus.h"

#include "core/image.h"
#include "io/atomic_file.h"
#include "io/gltf_io.h"
#include "io/image_io.h"
#include "pipeline/demo_asset.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <sys/stat.h>

namespace uvpress::test {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

void spit(const fs::path& p, const void* data, size_t n) {
  std::ofstream(p, std::ios::binary).write(static_cast<const char*>(data), std::streamsize(n));
}
void spit(const fs::path& p, const std::vector<uint8_t>& b) { spit(p, b.data(), b.size()); }
void spit(const fs::path& p, const std::string& s) { spit(p, s.data(), s.size()); }

uint32_t crc32(const uint8_t* p, size_t n) {
  uint32_t c = 0xffffffffu;
  for (size_t i = 0; i < n; ++i) {
    c ^= p[i];
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
  }
  return ~c;
}

void put_be32(std::vector<uint8_t>& b, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) b.push_back(uint8_t(v >> s));
}

// A PNG signature and an IHDR chunk (valid CRC) declaring width x height, then nothing.
std::vector<uint8_t> png_header_only(uint32_t width, uint32_t height) {
  std::vector<uint8_t> b = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  put_be32(b, 13);
  size_t type_at = b.size();
  b.insert(b.end(), {'I', 'H', 'D', 'R'});
  put_be32(b, width);
  put_be32(b, height);
  b.insert(b.end(), {8, 2, 0, 0, 0});  // 8-bit RGB
  put_be32(b, crc32(&b[type_at], 17));
  return b;
}

void put_le32(std::vector<uint8_t>& b, uint32_t v) {
  for (int s = 0; s < 32; s += 8) b.push_back(uint8_t(v >> s));
}

// Pointer to component c of element i of a float or uint16 accessor in the model.
uint8_t* element(tinygltf::Model& m, int accessor, size_t i, size_t c, size_t component_size) {
  const auto& a = m.accessors[size_t(accessor)];
  const auto& v = m.bufferViews[size_t(a.bufferView)];
  size_t width = size_t(tinygltf::GetNumComponentsInType(uint32_t(a.type)));
  size_t stride = v.byteStride ? v.byteStride : width * component_size;
  return m.buffers[size_t(v.buffer)].data.data() + v.byteOffset + a.byteOffset + i * stride + c * component_size;
}
void set_float(tinygltf::Model& m, int accessor, size_t i, size_t c, float value) {
  std::memcpy(element(m, accessor, i, c, 4), &value, 4);
}
void set_index(tinygltf::Model& m, int accessor, size_t i, uint16_t value) {
  std::memcpy(element(m, accessor, i, 0, 2), &value, 2);
}

}  // namespace

std::vector<uint8_t> png_with_text(std::vector<uint8_t> png, const std::string& text) {
  std::vector<uint8_t> chunk;
  put_be32(chunk, uint32_t(8 + text.size()));
  const size_t type_at = chunk.size();
  for (char c : std::string("tEXtComment", 11)) chunk.push_back(uint8_t(c));
  chunk.push_back(0);
  chunk.insert(chunk.end(), text.begin(), text.end());
  put_be32(chunk, crc32(&chunk[type_at], chunk.size() - type_at));
  png.insert(png.begin() + 33, chunk.begin(), chunk.end());  // after the signature and IHDR
  return png;
}

std::vector<uint8_t> make_glb(const std::string& json_text, const std::vector<uint8_t>& bin) {
  std::string j = json_text;
  j.resize((j.size() + 3) / 4 * 4, ' ');
  std::vector<uint8_t> b = bin;
  b.resize((b.size() + 3) / 4 * 4, 0);
  std::vector<uint8_t> out = {'g', 'l', 'T', 'F'};
  put_le32(out, 2);
  put_le32(out, uint32_t(12 + 8 + j.size() + 8 + b.size()));
  put_le32(out, uint32_t(j.size()));
  put_le32(out, 0x4E4F534Au);  // JSON
  out.insert(out.end(), j.begin(), j.end());
  put_le32(out, uint32_t(b.size()));
  put_le32(out, 0x004E4942u);  // BIN
  out.insert(out.end(), b.begin(), b.end());
  return out;
}

std::vector<CorpusCase> make_bad_input_corpus(const fs::path& dir) {
  std::vector<CorpusCase> cases;
  // The healthy asset in both forms.
  const io::GltfFile good = pipeline::make_demo_asset({4, 16});
  io::save_gltf(good, (dir / "good.glb").string());
  io::save_gltf(good, (dir / "good.gltf").string());
  const std::vector<uint8_t> glb = io::read_file((dir / "good.glb").string());
  const json base = json::parse(std::ifstream(dir / "good.gltf"));
  const auto& prim0 = good.model.meshes[0].primitives[0];
  const int pos = prim0.attributes.at("POSITION"), uv = prim0.attributes.at("TEXCOORD_0"), idx = prim0.indices;

  auto bytes_case = [&](const std::string& name, const std::string& ext, const std::vector<uint8_t>& bytes,
                        const std::string& reason) {
    fs::path f = dir / (name + ext);
    spit(f, bytes);
    cases.push_back({name, f, reason, false});
  };
  auto json_case = [&](const std::string& name, const std::function<void(json&)>& edit, const std::string& reason,
                       bool graceful = false) {
    json j = base;
    edit(j);
    fs::path f = dir / (name + ".gltf");
    spit(f, j.dump(1));
    cases.push_back({name, f, reason, graceful});
  };
  auto model_case = [&](const std::string& name, const std::function<void(io::GltfFile&)>& edit,
                        const std::string& reason, bool graceful = false) {
    io::GltfFile f = good;
    edit(f);
    // Keep declared bounds true (the validator checks them) so that only the intended
    // defect is in the file.
    for (int a : {pos, uv}) {
      auto& acc = f.model.accessors[size_t(a)];
      if (acc.minValues.empty()) continue;
      const size_t w = size_t(tinygltf::GetNumComponentsInType(uint32_t(acc.type)));
      acc.minValues.assign(w, INFINITY), acc.maxValues.assign(w, -INFINITY);
      for (size_t i = 0; i < acc.count; ++i)
        for (size_t c = 0; c < w; ++c) {
          float v;
          std::memcpy(&v, element(f.model, a, i, c, 4), 4);
          if (!std::isfinite(v)) continue;
          acc.minValues[c] = std::min(acc.minValues[c], double(v)), acc.maxValues[c] = std::max(acc.maxValues[c], double(v));
        }
    }
    fs::path p = dir / (name + ".gltf");
    io::save_gltf(f, p.string());
    cases.push_back({name, p, reason, graceful});
  };
  auto image_case = [&](const std::string& name, const std::string& file, const std::vector<uint8_t>* bytes,
                        const std::string& reason, const std::string& mime = "") {
    if (bytes) spit(dir / file, *bytes);
    json_case(name, [&](json& j) {
      j["images"][0] = {{"uri", file}};
      if (!mime.empty()) j["images"][0]["mimeType"] = mime;
    }, reason);
  };

  // --- Binary container ---
  bytes_case("truncated-half", ".glb", std::vector<uint8_t>(glb.begin(), glb.begin() + long(glb.size() / 2)), "");
  bytes_case("truncated-header", ".glb", std::vector<uint8_t>(glb.begin(), glb.begin() + 12), "truncated");
  bytes_case("empty", ".glb", {}, "empty");
  {
    auto b = glb;
    b[3] = 'X';
    bytes_case("wrong-magic", ".glb", b, "magic");
  }
  {
    auto b = glb;
    uint32_t huge = 0xfffffff0u;
    std::memcpy(&b[8], &huge, 4);  // total length
    bytes_case("absurd-glb-length", ".glb", b, "");
  }
  {
    auto b = glb;
    uint32_t huge = 0x7ffffff0u;
    std::memcpy(&b[12], &huge, 4);  // JSON chunk length
    bytes_case("absurd-chunk-length", ".glb", b, "");
  }
  {
    auto b = glb;
    uint32_t v = 1;
    std::memcpy(&b[4], &v, 4);
    bytes_case("glb-version-1", ".glb", b, "version 1");
  }
  {
    std::vector<uint8_t> b = {'g', 'l', 'T', 'F', 2, 0, 0, 0};
    for (uint32_t i = 0; i < 200; ++i) b.push_back(uint8_t(i * 37 + 11));
    bytes_case("garbage-after-magic", ".glb", b, "");
  }

  // --- JSON ---
  {
    std::string s = base.dump(1);
    bytes_case("bad-json", ".gltf", std::vector<uint8_t>(s.begin(), s.begin() + long(s.size() / 2)), "");
  }
  bytes_case("json-array", ".gltf", {'[', ']'}, "");
  json_case("version-1", [](json& j) { j["asset"]["version"] = "1.0"; }, "version");
  json_case("unknown-required-extension", [](json& j) {
    j["extensionsUsed"] = {"EXT_frobnicate"};
    j["extensionsRequired"] = {"EXT_frobnicate"};
  }, "EXT_frobnicate");
  json_case("draco-required", [](json& j) {
    j["extensionsUsed"] = {"KHR_draco_mesh_compression"};
    j["extensionsRequired"] = {"KHR_draco_mesh_compression"};
    j["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"] = {{"bufferView", 0}, {"attributes", {{"POSITION", 0}}}};
  }, "KHR_draco_mesh_compression");
  json_case("draco-optional", [](json& j) {
    j["extensionsUsed"] = {"KHR_draco_mesh_compression"};
    j["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"] = {{"bufferView", 0}, {"attributes", {{"POSITION", 0}}}};
  }, "Draco");

  // --- Accessors, views, buffers ---
  json_case("accessor-missing", [&](json& j) { j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 99; }, "");
  json_case("accessor-count-huge", [&](json& j) { j["accessors"][pos]["count"] = 1000000000; }, "");
  json_case("accessor-count-absurd", [&](json& j) { j["accessors"][uv]["count"] = 4294967295u; }, "");
  json_case("accessor-offset-outside", [&](json& j) { j["accessors"][pos]["byteOffset"] = 1 << 30; }, "");
  json_case("accessor-wrong-type", [&](json& j) { j["accessors"][pos]["type"] = "VEC2"; }, "");
  json_case("index-accessor-float", [&](json& j) { j["accessors"][idx]["componentType"] = 5126; }, "");
  json_case("bufferview-outside-buffer", [&](json& j) { j["bufferViews"][0]["byteLength"] = 1 << 28; }, "");
  json_case("buffer-missing-file", [](json& j) { j["buffers"][0]["uri"] = "nothere.bin"; }, "");
  json_case("buffer-length-absurd", [](json& j) { j["buffers"][0]["byteLength"] = 1e15; }, "");
  json_case("data-uri-broken", [](json& j) { j["buffers"][0]["uri"] = "data:application/octet-stream;base64,@@@@!!"; }, "");
  json_case("data-uri-short", [](json& j) {
    j["buffers"][0]["uri"] = "data:application/octet-stream;base64,AAAA";  // 3 bytes for a large byteLength
  }, "");
  json_case("sparse-count-out-of-range", [&](json& j) {
    j["accessors"][uv]["sparse"] = {{"count", j["accessors"][uv]["count"].get<int>() + 1},
                                    {"indices", {{"bufferView", j["accessors"][idx]["bufferView"]}, {"componentType", 5123}}},
                                    {"values", {{"bufferView", j["accessors"][uv]["bufferView"]}}}};
  }, "");
  model_case("index-out-of-range", [&](io::GltfFile& f) { set_index(f.model, idx, 4, 60000); }, "out of range");
  json_case("texcoord-count-differs", [&](json& j) {
    j["accessors"][uv]["count"] = j["accessors"][uv]["count"].get<int>() - 1;
  }, "count");
  json_case("texture-missing", [](json& j) { j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"] = 7; }, "");
  json_case("image-source-missing", [](json& j) { j["textures"][0]["source"] = 9; }, "");
  json_case("sampler-missing", [](json& j) { j["textures"][0]["sampler"] = 5; }, "");
  json_case("material-missing", [](json& j) { j["meshes"][0]["primitives"][0]["material"] = 3; }, "");
  json_case("texcoord-missing", [](json& j) { j["meshes"][0]["primitives"][0]["attributes"].erase("TEXCOORD_0"); }, "TEXCOORD_0");
  json_case("no-uvs-no-material", [](json& j) {
    j["meshes"][0]["primitives"][0]["attributes"].erase("TEXCOORD_0");
    j["meshes"][0]["primitives"][0].erase("material");
  }, "", true);
  json_case("points-primitive", [](json& j) { j["meshes"][0]["primitives"][0]["mode"] = 0; }, "", true);

  // --- Values ---
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  model_case("nan-position", [&](io::GltfFile& f) { set_float(f.model, pos, 3, 1, nan); }, "non-finite");
  model_case("inf-position", [&](io::GltfFile& f) { set_float(f.model, pos, 0, 0, -inf); }, "non-finite");
  model_case("nan-uv", [&](io::GltfFile& f) { set_float(f.model, uv, 2, 0, nan); }, "non-finite");
  model_case("inf-uv", [&](io::GltfFile& f) { set_float(f.model, uv, 5, 1, inf); }, "non-finite");
  model_case("zero-area-triangles", [&](io::GltfFile& f) {
    for (size_t i = 0; i < 6; ++i)  // the first row of vertices collapsed onto one point
      for (size_t c = 0; c < 3; ++c) set_float(f.model, pos, i, c, 0.25f);
  }, "", true);
  model_case("all-degenerate", [&](io::GltfFile& f) {
    const size_t n = f.model.accessors[size_t(pos)].count;
    for (size_t i = 0; i < n; ++i)
      for (size_t c = 0; c < 3; ++c) set_float(f.model, pos, i, c, 1.0f);
  }, "", true);
  model_case("zero-area-uvs", [&](io::GltfFile& f) {
    const size_t n = f.model.accessors[size_t(uv)].count;
    for (size_t i = 0; i < n; ++i) set_float(f.model, uv, i, 0, 0.5f), set_float(f.model, uv, i, 1, 0.5f);
  }, "", true);
  model_case("non-manifold", [&](io::GltfFile& f) {
    // Triangles 0..3 all use the edge (v0, v1): four faces on one edge.
    uint16_t v0, v1;
    std::memcpy(&v0, element(f.model, idx, 0, 0, 2), 2);
    std::memcpy(&v1, element(f.model, idx, 1, 0, 2), 2);
    for (size_t t = 1; t < 4; ++t) set_index(f.model, idx, 3 * t, v0), set_index(f.model, idx, 3 * t + 1, v1);
  }, "", true);

  // --- Images ---
  const std::vector<uint8_t> empty;
  const std::vector<uint8_t> corrupt = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R', 1, 2, 3};
  const std::vector<uint8_t> ktx2 = {0xab, 'K', 'T', 'X', ' ', '2', '0', 0xbb, '\r', '\n', 0x1a, '\n', 0, 0, 0, 0};
  const std::vector<uint8_t> text = {'h', 'e', 'l', 'l', 'o'};
  const std::vector<uint8_t> huge_header = png_header_only(100000, 100000);
  const std::vector<uint8_t> wide_header = png_header_only(16385, 16);
  Image wide;
  wide.width = 16385, wide.height = 1, wide.channels = 3;
  wide.pixels.assign(size_t(wide.width) * 3, 0.5f);
  const std::vector<uint8_t> wide_png = io::encode_image(wide, "png");
  image_case("image-missing", "gone.png", nullptr, "gone.png");
  image_case("image-empty", "empty.png", &empty, "");
  image_case("image-corrupt-png", "corrupt.png", &corrupt, "");
  image_case("image-ktx2", "texture.ktx2", &ktx2, "ktx2", "image/ktx2");
  image_case("image-not-an-image", "hello.png", &text, "");
  image_case("image-absurd-size", "absurd.png", &huge_header, "100000x100000");
  image_case("image-over-16k-header", "wide-header.png", &wide_header, "16384");
  image_case("image-over-16k", "wide.png", &wide_png, "16384");
  json_case("image-data-uri-broken", [](json& j) { j["images"][0] = {{"uri", "data:image/png;base64,%%%not-base64"}}; }, "");
  json_case("image-data-uri-empty", [](json& j) { j["images"][0] = {{"uri", "data:image/png;base64,"}}; }, "");
  json_case("image-bufferview-missing", [](json& j) { j["images"][0] = {{"bufferView", 42}, {"mimeType", "image/png"}}; }, "");
  {
    // PNG bytes in a bufferView that claims JPEG (tinygltf keeps a mimeType only there).
    uint32_t json_length;
    std::memcpy(&json_length, &glb[12], 4);
    json j = json::parse(glb.begin() + 20, glb.begin() + 20 + json_length);
    j["images"][0]["mimeType"] = "image/jpeg";
    const auto bin_at = glb.begin() + 20 + json_length + 8;
    bytes_case("image-mime-mismatch", ".glb", make_glb(j.dump(), std::vector<uint8_t>(bin_at, glb.end())), "mimeType");
  }

  // --- References (issue 13): uploads in dir/uploads reaching for files outside it ---
  const fs::path up = dir / "uploads";
  fs::create_directories(up);
  io::save_gltf(good, (up / "good.gltf").string());
  const std::vector<uint8_t> good_bin = io::read_file((up / base["buffers"][0]["uri"].get<std::string>()).string());
  const std::vector<uint8_t> secret_png = png_with_text(good.image_bytes[0], kOutsideMarker);
  std::vector<uint8_t> secret_bin = good_bin;
  secret_bin.insert(secret_bin.end(), kOutsideMarker.begin(), kOutsideMarker.end());
  spit(dir / "secret.png", secret_png);
  spit(dir / "secret.bin", secret_bin);
  auto upload_case = [&](const std::string& name, const std::function<void(json&)>& edit, const std::string& reason) {
    json j = base;
    edit(j);
    fs::path f = up / (name + ".gltf");
    spit(f, j.dump(1));
    cases.push_back({name, f, reason, false});
  };
  auto image_uri = [](const std::string& uri) { return [uri](json& j) { j["images"][0] = {{"uri", uri}}; }; };
  const std::string outside = "points outside the asset's folder";
  upload_case("ref-traversal", image_uri("../secret.png"), outside);
  upload_case("ref-traversal-etc", image_uri("../../../../../../../../../../etc/hostname"), outside);
  upload_case("ref-absolute", image_uri(fs::absolute(dir / "secret.png").string()), outside);
  fs::create_symlink(fs::absolute(dir / "secret.png"), up / "link.png");
  upload_case("ref-symlink-out", image_uri("link.png"), outside);
  upload_case("ref-percent-encoded", image_uri("..%2Fsecret.png"), outside);
  upload_case("ref-percent-dots", image_uri("%2e%2e/secret.png"), outside);
  upload_case("ref-buffer-traversal", [&](json& j) {
    j["buffers"][0] = {{"uri", "../secret.bin"}, {"byteLength", secret_bin.size()}};
  }, outside);
  ::mkfifo((up / "pipe.png").c_str(), 0644);
  upload_case("ref-fifo", image_uri("pipe.png"), "is a FIFO, not a regular file");
  ::mkfifo((up / "pipe.bin").c_str(), 0644);
  upload_case("ref-buffer-fifo", [&](json& j) { j["buffers"][0]["uri"] = "pipe.bin"; }, "is a FIFO, not a regular file");
  upload_case("ref-folder", image_uri("."), "is a folder, not a regular file");
  upload_case("ref-bad-escape", image_uri("tex%zz.png"), "percent-escape");
  spit(up / "notes.png", std::string("these are notes, not pixels\n"));
  upload_case("ref-not-an-image", image_uri("notes.png"), "not a PNG, JPEG, KTX2 or WebP image");
  // A sparse 64 GiB file: nothing may read it whole, whatever the buffer declares.
  const uint64_t huge = uint64_t(64) << 30;
  spit(up / "huge.bin", std::string());
  fs::resize_file(up / "huge.bin", huge);
  upload_case("ref-buffer-huge-sparse", [](json& j) { j["buffers"][0]["uri"] = "huge.bin"; }, "but the buffer declares byteLength");
  upload_case("ref-buffer-huge-declared", [&](json& j) {
    j["buffers"][0] = {{"uri", "huge.bin"}, {"byteLength", huge}};
  }, "uvpress reads for one buffer");
  {
    json j = base;  // a .glb whose image is an external file outside
    j["buffers"][0].erase("uri");
    j["images"][0] = {{"uri", "../secret.png"}};
    spit(up / "ref-glb-traversal.glb", make_glb(j.dump(), good_bin));
    cases.push_back({"ref-glb-traversal", up / "ref-glb-traversal.glb", outside, false});
  }
  return cases;
}

}  // namespace uvpress::test
