#include <catch2/catch.hpp>

#include "core/error.h"
#include "io/atomic_file.h"
#include "io/image_io.h"
#include "support.h"

#include <cmath>
#include <random>

using namespace uvpress;

namespace {

Image random_image(uint32_t w, uint32_t h, uint32_t channels, uint32_t bits, uint32_t seed) {
  std::mt19937 rng(seed);
  Image img;
  img.width = w, img.height = h, img.channels = channels, img.bits = bits;
  const uint32_t levels = bits == 16 ? 65535 : 255;
  img.pixels.resize(size_t(w) * h * channels);
  for (auto& v : img.pixels) v = float(rng() % (levels + 1)) / float(levels);
  return img;
}

}  // namespace

TEST_CASE("PNG round-trips exactly at 8 and 16 bits, with alpha kept straight", "[io][image]") {
  for (uint32_t bits : {8u, 16u})
    for (uint32_t channels : {1u, 2u, 3u, 4u}) {
      Image in = random_image(37, 21, channels, bits, bits * 10 + channels);
      // Zero alpha over non-zero colour: premultiplication on either side would erase it.
      if (channels == 4) in.at(0, 0, 3) = 0, in.at(0, 0, 0) = 1;
      auto bytes = io::encode_image(in, "png");
      CHECK(io::sniff_image_format(bytes.data(), bytes.size()) == "png");
      auto header = io::read_image_header(bytes, "test");
      CHECK(header.width == 37);
      CHECK(header.height == 21);
      CHECK(header.channels == channels);
      CHECK(header.bits == bits);
      Image out = io::decode_image(bytes, "test");
      REQUIRE(out.pixels.size() == in.pixels.size());
      CHECK(out.bits == bits);
      for (size_t i = 0; i < in.pixels.size(); ++i) REQUIRE(std::abs(out.pixels[i] - in.pixels[i]) < 1e-7f);
    }
}

TEST_CASE("JPEG encodes and decodes close to the source", "[io][image]") {
  Image in;
  in.width = 64, in.height = 48, in.channels = 3;
  in.pixels.resize(64 * 48 * 3);
  for (uint32_t y = 0; y < 48; ++y)
    for (uint32_t x = 0; x < 64; ++x)
      for (uint32_t c = 0; c < 3; ++c) in.at(x, y, c) = 0.5f + 0.4f * std::sin(0.1f * float(x * (c + 1)) + 0.07f * float(y));
  auto bytes = io::encode_image(in, "jpeg");
  CHECK(io::sniff_image_format(bytes.data(), bytes.size()) == "jpeg");
  Image out = io::decode_image(bytes, "test");
  REQUIRE(out.pixels.size() == in.pixels.size());
  double err = 0;
  for (size_t i = 0; i < in.pixels.size(); ++i) err += std::abs(out.pixels[i] - in.pixels[i]);
  CHECK(err / double(in.pixels.size()) < 0.01);
}

TEST_CASE("Unsupported, empty and corrupt images give a clear InputError", "[io][image]") {
  const std::vector<uint8_t> ktx2 = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n', 0, 0, 0, 0};
  CHECK(io::sniff_image_format(ktx2.data(), ktx2.size()) == "ktx2");
  CHECK_THROWS_WITH(io::decode_image(ktx2, "x"), Catch::Contains("ktx2"));
  CHECK_THROWS_WITH(io::decode_image({}, "x"), Catch::Contains("empty"));
  CHECK_THROWS_AS(io::decode_image({1, 2, 3, 4, 5}, "x"), InputError);
  auto png = io::encode_image(random_image(64, 64, 3, 8, 1), "png");
  png.resize(png.size() / 2);
  CHECK_THROWS_AS(io::decode_image(png, "x"), InputError);
}

TEST_CASE("Duck's texture decodes as 512x512 RGB", "[io][image][shared]") {
  auto shared = test::shared_dir();
  if (!shared) UVPRESS_SKIP("../shared is absent");
  auto bytes = io::read_file((*shared / "assets/Duck/glTF/DuckCM.png").string());
  Image img = io::decode_image(bytes, "DuckCM.png");
  CHECK(img.width == 512);
  CHECK(img.height == 512);
  CHECK(img.channels == 3);
}
