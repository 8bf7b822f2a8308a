// The sample kernel pair (GMSD steps 1-2) on both backends against an independent
// double-precision reference written from reference/gmsd.md, and the Vulkan path on
// lavapipe with the validation layer on.
#include <catch2/catch.hpp>

#include "engine.h"
#include "support.h"

#include <cmath>
#include <random>

using namespace uvpress::engine;

namespace {

std::vector<uint32_t> random_images(uint32_t w, uint32_t h, uint32_t count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<uint32_t> px(size_t(w) * h * count);
  for (auto& p : px) p = rng();
  return px;
}

// gmsd.md 1-2 in double: Y = 0.299R + 0.587G + 0.114B on [0,1] values; 2x2 mean, zero outside.
void reference(const std::vector<uint32_t>& px, uint32_t w, uint32_t h, uint32_t count, std::vector<double>& y,
               std::vector<double>& d) {
  uint32_t w2 = (w + 1) / 2, h2 = (h + 1) / 2;
  y.assign(px.size(), 0);
  d.assign(size_t(w2) * h2 * count, 0);
  for (size_t i = 0; i < px.size(); ++i)
    y[i] = (0.299 * (px[i] & 255) + 0.587 * ((px[i] >> 8) & 255) + 0.114 * ((px[i] >> 16) & 255)) / 255.0;
  for (uint32_t k = 0; k < count; ++k)
    for (uint32_t j = 0; j < h2; ++j)
      for (uint32_t i = 0; i < w2; ++i) {
        double s = 0;
        for (uint32_t dy = 0; dy < 2; ++dy)
          for (uint32_t dx = 0; dx < 2; ++dx) {
            uint32_t x = 2 * i + dx, yy = 2 * j + dy;
            if (x < w && yy < h) s += y[size_t(k) * w * h + size_t(yy) * w + x];
          }
        d[size_t(k) * w2 * h2 + size_t(j) * w2 + i] = s / 4;
      }
}

double max_diff(const std::vector<float>& a, const std::vector<double>& b) {
  REQUIRE(a.size() == b.size());
  double m = 0;
  for (size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(double(a[i]) - b[i]));
  return m;
}

double max_diff(const std::vector<float>& a, const std::vector<float>& b) {
  REQUIRE(a.size() == b.size());
  double m = 0;
  for (size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(double(a[i]) - double(b[i])));
  return m;
}

}  // namespace

TEST_CASE("CPU luminance and downsample match the double-precision definition", "[engine]") {
  for (auto [w, h] : {std::pair{64u, 64u}, {7u, 9u}, {1u, 1u}, {33u, 2u}}) {
    const uint32_t count = 5;
    auto px = random_images(w, h, count, w * 31 + h);
    std::vector<double> y, d;
    reference(px, w, h, count, y, d);
    auto out = make_cpu_engine({})->luminance({w, h, count, px.data()});
    CHECK(max_diff(out.full, y) < 1e-6);
    CHECK(max_diff(out.half, d) < 1e-6);
  }
}

TEST_CASE("CPU backend gives identical results for any thread count", "[engine]") {
  auto px = random_images(20, 13, 37, 3);
  EngineOptions one, many;
  one.threads = 1, many.threads = 7;
  auto a = make_cpu_engine(one)->luminance({20, 13, 37, px.data()});
  auto b = make_cpu_engine(many)->luminance({20, 13, 37, px.data()});
  CHECK(a.full == b.full);
  CHECK(a.half == b.half);
}

TEST_CASE("Vulkan on lavapipe matches the CPU backend with zero validation errors", "[engine][vulkan]") {
  UVPRESS_LAVAPIPE_OR_SKIP(gpu);
  auto info = gpu->device();
  CHECK(info.backend == "vulkan");
  CHECK((info.type == "cpu") != uvpress::test::vulkan_tests_on_gpu());
  auto cpu = make_cpu_engine({});
  for (auto [w, h] : {std::pair{64u, 64u}, {7u, 9u}, {1u, 1u}, {100u, 3u}}) {
    const uint32_t count = 11;
    auto px = random_images(w, h, count, w + 7 * h);
    Rgba8Batch batch{w, h, count, px.data()};
    auto a = gpu->luminance(batch), b = cpu->luminance(batch);
    std::vector<double> y, d;
    reference(px, w, h, count, y, d);
    CHECK(max_diff(a.full, b.full) < 1e-6);
    CHECK(max_diff(a.half, b.half) < 1e-6);
    CHECK(max_diff(a.full, y) < 1e-6);
    CHECK(max_diff(a.half, d) < 1e-6);
  }
  CHECK(gpu->validation_errors() == 0);
}

TEST_CASE("Vulkan batches larger than a buffer are chunked with identical results", "[engine][vulkan]") {
  const uint32_t w = 32, h = 32, count = 50;
  auto px = random_images(w, h, count, 99);
  Rgba8Batch batch{w, h, count, px.data()};
  UVPRESS_LAVAPIPE_OR_SKIP(whole_engine);
  auto whole = whole_engine->luminance(batch);
  // 7 images per buffer: 8 chunks, the last one partial.
  auto chunked_engine = uvpress::test::lavapipe(7 * w * h * 4);
  auto chunked = chunked_engine->luminance(batch);
  CHECK(chunked.full == whole.full);
  CHECK(chunked.half == whole.half);
  // Buffers are reused across calls, including a smaller batch after a larger one.
  auto again = chunked_engine->luminance({w, h, 3, px.data()});
  CHECK(std::equal(again.full.begin(), again.full.end(), whole.full.begin()));
  CHECK(chunked_engine->validation_errors() == 0);
}

TEST_CASE("An empty batch is fine on both backends", "[engine][vulkan]") {
  Rgba8Batch empty{8, 8, 0, nullptr};
  CHECK(make_cpu_engine({})->luminance(empty).full.empty());
  UVPRESS_LAVAPIPE_OR_SKIP(gpu);
  CHECK(gpu->luminance(empty).half.empty());
  CHECK(gpu->validation_errors() == 0);
}

TEST_CASE("Device requests parse and resolve", "[engine]") {
  CHECK(parse_device_request("auto") == DeviceRequest::Auto);
  CHECK(parse_device_request("gpu") == DeviceRequest::Gpu);
  CHECK(parse_device_request("lavapipe") == DeviceRequest::Lavapipe);
  CHECK(parse_device_request("cpu") == DeviceRequest::Cpu);
  CHECK_FALSE(parse_device_request("cuda"));
  CHECK(make_engine(DeviceRequest::Cpu, {})->device().backend == "cpu");
  CHECK(make_engine(DeviceRequest::Lavapipe, {})->device().type == "cpu");
  // Auto takes a real GPU when Vulkan has one, otherwise the native backend, never lavapipe.
  auto chosen = make_engine(DeviceRequest::Auto, {})->device();
  CHECK((chosen.backend == "cpu" || chosen.type != "cpu"));
  CHECK_THROWS_AS(make_vulkan_engine(DeviceRequest::Cpu, {}), EngineError);
}
