// External references (issue 13): the containment rule every reader applies, and the check
// on images carried byte for byte. End-to-end cases are in the bad-input corpus.
#include <catch2/catch.hpp>

#include "core/error.h"
#include "io/image_io.h"
#include "io/references.h"
#include "support.h"

#include <fstream>
#include <sys/stat.h>

using namespace uvpress;

namespace {

std::string reason(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

void write(const test::fs::path& p, const std::string& bytes) { std::ofstream(p, std::ios::binary) << bytes; }

}  // namespace

TEST_CASE("percent_decode: RFC 3986 escapes, nothing else", "[io][refs]") {
  CHECK(io::percent_decode("a%20b.png") == "a b.png");
  CHECK(io::percent_decode("..%2Fx") == "../x");
  CHECK(io::percent_decode("%2e%2E/x") == "../x");
  CHECK(io::percent_decode("a+b.png") == "a+b.png");
  CHECK_THROWS_AS(io::percent_decode("x%2"), std::invalid_argument);
  CHECK_THROWS_AS(io::percent_decode("x%zz"), std::invalid_argument);
  CHECK_THROWS_AS(io::percent_decode("x%00.png"), std::invalid_argument);
}

TEST_CASE("external_refs: buffer and image URIs of .gltf JSON, data: URIs excluded", "[io][refs]") {
  const std::string j = R"({"buffers":[{"uri":"a.bin","byteLength":12},{"uri":"data:application/octet-stream;base64,AAAA"}],
                            "images":[{"uri":"t%20x.png"},{"bufferView":0,"mimeType":"image/png"}]})";
  auto refs = io::external_refs(std::vector<uint8_t>(j.begin(), j.end()));
  REQUIRE(refs.size() == 2);
  CHECK(refs[0].what == "buffer 0");
  CHECK(refs[0].buffer);
  CHECK(refs[0].byte_length == 12);
  CHECK(refs[1].what == "image 0");
  CHECK(refs[1].uri == "t%20x.png");
  CHECK(io::external_refs(std::vector<uint8_t>{'{', 'x'}).empty());
}

TEST_CASE("open_ref: inside the asset's folder, regular, within its size, or one reason", "[io][refs]") {
  test::Scratch dir("refs");
  test::fs::create_directories(dir / "up" / "sub");
  const std::string asset = (dir / "up" / "a.gltf").string();
  write(dir / "up" / "sub" / "t x.png", "12345");
  write(dir / "secret.txt", "secret");
  test::fs::create_symlink(dir / "secret.txt", dir / "up" / "link.png");
  test::fs::create_symlink("sub/t x.png", dir / "up" / "inner.png");
  REQUIRE(::mkfifo((dir / "up" / "fifo.bin").c_str(), 0644) == 0);
  auto image = [](const std::string& uri) { return io::ExternalRef{"image 3", uri, false, -1}; };
  auto open = [&](const io::ExternalRef& r, bool allow = false) { return reason([&] { io::open_ref(asset, r, {allow}); }); };

  auto ok = io::open_ref(asset, image("sub/t%20x.png"), {});
  CHECK(ok.file.size() == 5);
  CHECK(ok.file.read_all() == std::vector<uint8_t>{'1', '2', '3', '4', '5'});
  CHECK(open(image("sub/../sub/t%20x.png")).empty());
  CHECK(open(image("inner.png")).empty());  // a link that stays inside is fine

  const std::string outside = "points outside the asset's folder";
  CHECK(open(image("../secret.txt")) == "image 3: '../secret.txt' " + outside);
  CHECK_THAT(open(image("sub/../../secret.txt")), Catch::Contains(outside));
  CHECK_THAT(open(image("..%2fsecret.txt")), Catch::Contains(outside));
  CHECK_THAT(open(image((dir / "secret.txt").string())), Catch::Contains(outside));
  CHECK_THAT(open(image("link.png")), Catch::Contains(outside));
  CHECK_THAT(open(image("nothere/../../secret.txt")), Catch::Contains(outside));
  CHECK(open(image("link.png"), true).empty());  // --allow-outside-refs

  // A missing file says where it was looked for (the asset's folder).
  CHECK(open(image("gone.png")) == "image 3: 'gone.png' not found (looked for " +
                                       (test::fs::canonical(dir / "up") / "gone.png").string() + ")");
  CHECK(open(image("sub")) == "image 3: 'sub' is a folder, not a regular file");
  CHECK(open(image("fifo.bin")) == "image 3: 'fifo.bin' is a FIFO, not a regular file");
  CHECK(open(image("/dev/null"), true) == "image 3: '/dev/null' is a device, not a regular file");
  CHECK_THAT(open(image("a\nb%zz")), Catch::Contains("'a?b%zz' is not a valid URI"));  // still one line

  CHECK(open({"buffer 0", "sub/t%20x.png", true, 5}).empty());
  CHECK(open({"buffer 0", "sub/t%20x.png", true, 4}) == "buffer 0: 'sub/t%20x.png' is 5 bytes, but the buffer declares byteLength 4");
  CHECK_THAT(open({"buffer 0", "sub/t%20x.png", true, int64_t(1) << 40}), Catch::Contains("uvpress reads for one buffer"));
}

TEST_CASE("check_image: carried images are the format their bytes and mimeType claim", "[io][refs]") {
  Image img;
  img.width = 8, img.height = 4, img.channels = 3;
  img.pixels.assign(8 * 4 * 3, 0.5f);
  const auto png = io::encode_image(img, "png"), jpeg = io::encode_image(img, "jpeg");
  auto check = [](const std::vector<uint8_t>& b, const std::string& mime) {
    return reason([&] { io::check_image(b, mime, "a.gltf"); });
  };
  CHECK(check(png, "").empty());
  CHECK(check(png, "image/png").empty());
  CHECK(check(jpeg, "image/jpeg").empty());
  CHECK(check(jpeg, "image/jpg").empty());
  CHECK(check(png, "image/jpeg") == "holds png data, but its mimeType says 'image/jpeg'");
  CHECK(check({'h', 'i'}, "") == "is not a PNG, JPEG, KTX2 or WebP image (unrecognized data)");
  CHECK_THAT(check({'G', 'I', 'F', '8', '9', 'a'}, ""), Catch::Contains("gif data"));
  auto truncated = png;
  truncated.resize(40);
  CHECK_FALSE(check(truncated, "").empty());

  // KTX2 and WebP are carried, not decoded: their headers must give a size within limits.
  std::vector<uint8_t> ktx2 = {0xab, 'K', 'T', 'X', ' ', '2', '0', 0xbb, '\r', '\n', 0x1a, '\n'};
  ktx2.resize(80, 0);
  ktx2[20] = 0x00, ktx2[21] = 0x01, ktx2[24] = 0x40;  // 256 x 64
  CHECK(check(ktx2, "image/ktx2").empty());
  ktx2[22] = 0x01;  // 65792 wide
  CHECK_THAT(check(ktx2, "image/ktx2"), Catch::Contains("16384"));
  std::vector<uint8_t> webp = {'R', 'I', 'F', 'F', 0, 0, 0, 0, 'W', 'E', 'B', 'P', 'V', 'P', '8', 'X'};
  webp.resize(30, 0);
  webp[24] = 99, webp[27] = 49;  // 100 x 50
  CHECK(check(webp, "image/webp").empty());
  webp.resize(20);
  CHECK_THAT(check(webp, ""), Catch::Contains("corrupt webp"));
}
