// GPU-ready output (issue 18, item 4): ASTC KTX2 files that an independent reader accepts
// (npm's ktx-parse, tools/ktx2-inspect.mjs: vkFormat, sizes, data format descriptor, level
// index), whose payload the astcenc command decodes to the texels uvpress decodes, within
// astcenc's own error for the preset; the KTX2 copies beside a glTF (image extras), carried
// by load and save, dropped once their image is re-baked, and accepted by the validator.
// --texture-format astc on the command line: tests/cli/test_ktx2.cpp.
#include <catch2/catch.hpp>

#include "io/astc_codec.h"
#include "io/atomic_file.h"
#include "io/gltf_io.h"
#include "io/gpu_textures.h"
#include "io/image_io.h"
#include "io/ktx2.h"
#include "pipeline/demo_asset.h"
#include "support.h"

#include <cmath>
#include <cstdio>
#include <fstream>

using namespace uvpress;
namespace fs = std::filesystem;

namespace {

using test::quoted;

// Runs a shell command; stdout, and the exit code in *code.
std::string shell(const std::string& command, int* code) {
  std::string out;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return out;
  char buf[4096];
  for (size_t n; (n = fread(buf, 1, sizeof buf, pipe)) > 0;) out.append(buf, n);
  *code = pclose(pipe);
  return out;
}

bool have(const std::string& command) {
  int code = -1;
  shell("command -v " + command + " >/dev/null", &code);
  return code == 0;
}

// ktx-parse's view of a KTX2 file (tools/ktx2-inspect.mjs); with astc_prefix, each level's
// payload as PREFIX<level>.astc too.
nlohmann::json inspect(const fs::path& ktx2, const fs::path& astc_prefix = {}) {
  const fs::path script = fs::path(UVPRESS_SOURCE_DIR) / "tools" / "ktx2-inspect.mjs";
  int code = -1;
  std::string out = shell("node " + quoted(script) + " " + quoted(ktx2) +
                              (astc_prefix.empty() ? "" : " --astc-out " + quoted(astc_prefix)),
                          &code);
  if (code != 0) throw std::runtime_error("ktx2-inspect did not run (run tools/install-deps.sh): " + out);
  return nlohmann::json::parse(out);
}

// Smooth colour with detail, 8-bit values; alpha (4 channels) varies too.
Image test_image(uint32_t w, uint32_t h, uint32_t channels) {
  return test::smooth_image(w, h, channels, false, {0.09f, 0.05f, 0.41f});
}

// The first `channels` channels of `image` (a decoder may add alpha).
Image first_channels(const Image& image, uint32_t channels) {
  Image out = image;
  out.channels = channels;
  out.pixels.resize(size_t(image.width) * image.height * channels);
  for (size_t i = 0; i < size_t(image.width) * image.height; ++i)
    for (uint32_t c = 0; c < channels; ++c) out.pixels[i * channels + c] = image.pixels[i * image.channels + c];
  return out;
}

void write_bytes(const fs::path& path, const std::vector<uint8_t>& bytes) {
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

// The .ktx2 files in a folder.
std::vector<fs::path> ktx2_files(const fs::path& dir) {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".ktx2") out.push_back(e.path());
  return out;
}

float max_abs_diff(const Image& a, const Image& b) {
  float m = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) m = std::max(m, std::abs(a.pixels[i] - b.pixels[i]));
  return m;
}

}  // namespace

TEST_CASE("KTX2 ASTC: ktx-parse reads header, descriptor and level index, astcenc decodes the payload within its own error",
          "[io][ktx2]") {
  if (!have("astcenc")) FAIL("the astcenc command is missing (run tools/install-deps.sh)");
  test::Scratch dir("ktx2-astc");
  struct Case {
    uint32_t bx, by, channels;
    bool srgb;
    io::AstcQuality quality;
  };
  // Sides that are not multiples of the block (partial blocks at the edges), sRGB colour and
  // linear data with a varying alpha.
  for (const Case& k : {Case{6, 6, 3, true, io::AstcQuality::Medium}, Case{4, 4, 4, false, io::AstcQuality::Fast},
                        Case{8, 8, 3, true, io::AstcQuality::Medium}, Case{5, 4, 3, false, io::AstcQuality::Fastest}}) {
    const io::AstcOptions o{k.bx, k.by, k.quality};
    const std::string tag = io::block_name(o) + (k.srgb ? "-srgb" : "-unorm");
    INFO(tag);
    const Image img = test_image(70, 45, k.channels);
    Image decoded;
    const auto bytes = io::encode_ktx2_astc(img, k.srgb, o, &decoded);
    const fs::path file = dir / (tag + ".ktx2"), src = dir / (tag + ".png");
    write_bytes(file, bytes);
    write_bytes(src, io::encode_image(img, "png"));

    const auto j = inspect(file, dir / (tag + "-level"));
    CHECK(j["vkFormat"] == io::astc_vk_format(k.bx, k.by, k.srgb));
    CHECK(j["typeSize"] == 1);
    CHECK(j["pixelWidth"] == 70);
    CHECK(j["pixelHeight"] == 45);
    CHECK(j["pixelDepth"] == 0);
    CHECK(j["layerCount"] == 0);
    CHECK(j["faceCount"] == 1);
    CHECK(j["supercompressionScheme"] == 0);
    CHECK(j["levelCount"] == 7);  // 70 -> 35 -> 17 -> 8 -> 4 -> 2 -> 1
    const auto& d = j["dfd"];
    CHECK(d["vendorId"] == 0);
    CHECK(d["descriptorType"] == 0);
    CHECK(d["versionNumber"] == 2);
    CHECK(d["colorModel"] == 162);  // KHR_DF_MODEL_ASTC
    CHECK(d["colorPrimaries"] == 1);
    CHECK(d["transferFunction"] == (k.srgb ? 2 : 1));
    CHECK(d["texelBlockDimension"] == nlohmann::json::array({k.bx - 1, k.by - 1, 0, 0}));
    CHECK(d["bytesPlane"][0] == 16);
    REQUIRE(d["samples"].size() == 1);
    CHECK(d["samples"][0]["bitLength"] == 127);
    CHECK(d["samples"][0]["channelType"] == 0);
    CHECK(j["keyValue"]["KTXwriter"] == "uvpress");
    // Level index: sizes of whole blocks, no supercompression, 16-byte aligned offsets, the
    // smallest level first in the file, levels disjoint and inside the file.
    uint64_t previous_offset = j["byteLength"].get<uint64_t>() + 1;
    for (uint32_t l = 0; l < 7; ++l) {
      const auto& L = j["levels"][l];
      const uint32_t w = std::max(1u, 70u >> l), h = std::max(1u, 45u >> l);
      CHECK(L["byteLength"] == io::astc_bytes(w, h, k.bx, k.by));
      CHECK(L["uncompressedByteLength"] == L["byteLength"]);
      const uint64_t at = L["byteOffset"].get<uint64_t>();
      CHECK(at % 16 == 0);
      CHECK(at + L["byteLength"].get<uint64_t>() <= previous_offset);
      previous_offset = at;
    }
    CHECK(j["levels"][0]["byteOffset"].get<uint64_t>() + j["levels"][0]["byteLength"].get<uint64_t>() == bytes.size());

    // The astcenc command decodes each level's payload as ktx-parse found it: the texels
    // uvpress's own decode gives, level 0 and a coarse one.
    const std::string profile = k.srgb ? "s" : "l";
    for (uint32_t l : {0u, 3u}) {
      const fs::path out = dir / (tag + "-d" + std::to_string(l) + ".png");
      int code = -1;
      const auto log = shell("astcenc -d" + profile + " " + quoted(dir / (tag + "-level" + std::to_string(l) + ".astc")) +
                                 " " + quoted(out) + " -silent",
                             &code);
      INFO(log);
      REQUIRE(code == 0);
      const Image theirs = first_channels(io::decode_image(io::read_file(out.string()), out.string()), k.channels);
      const Image ours = io::decode_ktx2_level(bytes, l, k.channels, file.string());
      REQUIRE(theirs.width == ours.width);
      REQUIRE(theirs.height == ours.height);
      // The same 8-bit values (the two decoders scale them to floats differently).
      CHECK(max_abs_diff(theirs, ours) < 1e-6f);
      if (l == 0) CHECK(max_abs_diff(ours, decoded) < 1e-6f);
    }
    // Level 0 against the source: within astcenc's own error at this footprint and preset
    // (its command compressing and decoding the same PNG).
    const fs::path own = dir / (tag + "-own.png");
    int code = -1;
    const char* preset = k.quality == io::AstcQuality::Medium ? "-medium" : k.quality == io::AstcQuality::Fast ? "-fast" : "-fastest";
    const auto log = shell("astcenc -t" + profile + " " + quoted(src) + " " + quoted(own) + " " + io::block_name(o) + " " +
                               preset + " -silent",
                           &code);
    INFO(log);
    REQUIRE(code == 0);
    const Image astcenc_own = first_channels(io::decode_image(io::read_file(own.string()), own.string()), k.channels);
    const double ours = io::rmse_8bit(img, decoded), theirs = io::rmse_8bit(img, astcenc_own);
    INFO("RMSE uvpress " << ours << ", astcenc " << theirs);
    CHECK(ours > 0);
    CHECK(ours <= 1.05 * theirs + 0.05);
  }
}

TEST_CASE("KTX2 copies beside a glTF: named in the image's extras, carried by load and save, dropped once re-baked",
          "[io][ktx2]") {
  test::Scratch dir("ktx2-sidecar");
  io::GltfFile demo = pipeline::make_demo_asset({8, 32});
  io::save_gltf(demo, (dir / "in.gltf").string());
  io::GltfFile file = io::load_gltf((dir / "in.gltf").string());
  const auto infos = io::attach_astc_textures(file, {6, 6, io::AstcQuality::Fast});
  REQUIRE(infos.size() == file.image_bytes.size());
  REQUIRE(!infos.empty());
  CHECK(infos[0].vk_format == io::astc_vk_format(6, 6, true));  // base colour: sRGB
  CHECK(infos[0].psnr_db > 25);
  io::save_gltf(file, (dir / "out.gltf").string());
  std::ifstream in(dir / "out.gltf");
  const auto json = nlohmann::json::parse(in);
  const auto& entry = json["images"][0]["extras"]["uvpress_ktx2"];
  REQUIRE(entry.is_object());
  CHECK(entry["mimeType"] == "image/ktx2");
  const fs::path ktx2 = dir / entry["uri"].get<std::string>();
  REQUIRE(fs::exists(ktx2));
  CHECK(entry["byteLength"] == fs::file_size(ktx2));
  CHECK(io::read_ktx2(io::read_file(ktx2.string()), ktx2.string()).vk_format == io::astc_vk_format(6, 6, true));
  // The validator accepts it and says nothing it did not say of the input.
  const auto v_in = test::validate_gltf(dir / "in.gltf"), v_out = test::validate_gltf(dir / "out.gltf");
  CHECK(v_out["numErrors"] == 0);
  CHECK(v_out["codes"] == v_in["codes"]);

  // Loaded again and saved as .glb: the copy comes along, byte for byte.
  io::GltfFile again = io::load_gltf((dir / "out.gltf").string());
  REQUIRE(again.image_ktx2.size() == 1);
  CHECK(again.image_ktx2[0].bytes == io::read_file(ktx2.string()));
  fs::create_directories(dir / "b");
  fs::create_directories(dir / "c");
  io::save_gltf(again, (dir / "b" / "out.glb").string());
  const auto beside_glb = ktx2_files(dir / "b");
  REQUIRE(beside_glb.size() == 1);
  CHECK(io::read_file(beside_glb[0].string()) == again.image_ktx2[0].bytes);
  io::GltfFile glb = io::load_gltf((dir / "b" / "out.glb").string());
  CHECK(glb.image_ktx2[0].bytes == again.image_ktx2[0].bytes);
  CHECK(test::validate_gltf(dir / "b" / "out.glb")["numErrors"] == 0);

  // Re-baked (its bytes changed): the copy no longer shows the image and is not written.
  again.image_bytes[0] = io::encode_image(test_image(32, 32, 3), "png");
  io::save_gltf(again, (dir / "c" / "out.gltf").string());
  CHECK(ktx2_files(dir / "c").empty());
  std::ifstream in2(dir / "c" / "out.gltf");
  const auto json2 = nlohmann::json::parse(in2);
  CHECK(!json2["images"][0].contains("extras"));
  // A copy that is missing is dropped on load; the glTF loads.
  fs::remove(ktx2);
  CHECK(io::load_gltf((dir / "out.gltf").string()).image_ktx2[0].bytes.empty());
}
