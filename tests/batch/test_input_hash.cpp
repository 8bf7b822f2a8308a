// batch's input hashes (batch/input_hash.h): a .glb's external files are part of them,
// read by the loader's rule.
#include <catch2/catch.hpp>

#include "batch/corpus.h"
#include "batch/input_hash.h"
#include "io/gltf_io.h"
#include "pipeline/demo_asset.h"
#include "support.h"

#include <fstream>
#include <sys/stat.h>

using namespace uvpress;
using json = nlohmann::json;

using test::read_json;

TEST_CASE("batch: input hashes cover a .glb's external files, read by the loader's rule", "[batch]") {
  test::Scratch dir("hash-refs");
  test::fs::create_directories(dir / "up");
  io::save_gltf(pipeline::make_demo_asset({4, 16}), (dir / "up" / "demo.gltf").string());
  json j = read_json(dir / "up" / "demo.gltf");
  std::ifstream bin(dir / "up" / j["buffers"][0]["uri"].get<std::string>(), std::ios::binary);
  const std::vector<uint8_t> bin_bytes(std::istreambuf_iterator<char>(bin), {});
  test::fs::copy_file(dir / "up" / j["images"][0]["uri"].get<std::string>(), dir / "up" / "tex.png");
  test::fs::copy_file(dir / "up" / "tex.png", dir / "outside.png");
  j["buffers"][0].erase("uri");
  const auto glb_with = [&](const std::string& uri, const std::string& name) {
    j["images"][0] = {{"uri", uri}};
    const auto glb = test::make_glb(j.dump(), bin_bytes);
    const auto path = dir / "up" / name;
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(glb.data()), std::streamsize(glb.size()));
    return path.string();
  };
  const std::string inside = glb_with("tex.png", "inside.glb"), outside = glb_with("../outside.png", "outside.glb");
  CHECK(io::load_gltf(inside).image_bytes[0].size() == test::fs::file_size(dir / "up" / "tex.png"));

  // A .glb's external image is part of its input hash.
  const std::string h = batch::hash_asset(inside);
  std::ofstream(dir / "up" / "tex.png", std::ios::app) << "x";
  CHECK(batch::hash_asset(inside) != h);

  // A FIFO is never opened (the hash would block forever), yet changes the hash.
  test::fs::remove(dir / "up" / "tex.png");
  REQUIRE(::mkfifo((dir / "up" / "tex.png").c_str(), 0644) == 0);
  const std::string fifo = batch::hash_asset(inside);
  CHECK_FALSE(fifo.empty());
  CHECK(fifo != h);

  // A file outside the folder is read only when the policy allows it.
  const std::string refused = batch::hash_asset(outside), allowed = batch::hash_asset(outside, {true});
  std::ofstream(dir / "outside.png", std::ios::app) << "x";
  CHECK(batch::hash_asset(outside) == refused);
  CHECK(batch::hash_asset(outside, {true}) != allowed);
}
