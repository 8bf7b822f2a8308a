#include <catch2/catch.hpp>

#include "io/image_io.h"
#include "pipeline/demo_asset.h"
#include "pipeline/inspect.h"
#include "support.h"

#include <cmath>

using namespace uvpress;

namespace {

// Mean absolute horizontal + vertical difference of luminance over a pixel rectangle.
double detail(const Image& img, uint32_t x0, uint32_t x1, uint32_t y0, uint32_t y1) {
  auto lum = [&](uint32_t x, uint32_t y) {
    return 0.299 * img.at(x, y, 0) + 0.587 * img.at(x, y, 1) + 0.114 * img.at(x, y, 2);
  };
  double sum = 0;
  for (uint32_t y = y0; y + 1 < y1; ++y)
    for (uint32_t x = x0; x + 1 < x1; ++x)
      sum += std::abs(lum(x + 1, y) - lum(x, y)) + std::abs(lum(x, y + 1) - lum(x, y));
  return sum / double((x1 - x0 - 1) * (y1 - y0 - 1));
}

}  // namespace

TEST_CASE("The demo asset is deterministic, valid, one chart, with flat and detailed texture", "[pipeline][demo]") {
  io::GltfFile a = pipeline::make_demo_asset(), b = pipeline::make_demo_asset();
  CHECK(a.image_bytes == b.image_bytes);
  CHECK(a.model.buffers[0].data == b.model.buffers[0].data);

  test::Scratch dir("demo");
  auto path = dir / "demo.glb";
  io::save_gltf(a, path.string());
  auto report = test::validate_gltf(path);
  CHECK(report["numErrors"] == 0);

  auto info = pipeline::inspect(io::load_gltf(path.string()));
  CHECK(info["triangles"] == 2 * 48 * 48);
  CHECK(info["primitives"][0]["uv_sets"][0]["charts"] == 1);
  CHECK(info["images"][0]["width"] == 512);

  Image tex = io::decode_image(a.image_bytes[0], "demo");
  // Flat area (left, away from the badge and the edge) vs fine detail (right).
  double flat = detail(tex, 10, 150, 300, 500), fine = detail(tex, 330, 500, 10, 500);
  CHECK(flat < 1e-3);
  CHECK(fine > 0.1);
}
