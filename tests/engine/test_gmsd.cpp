// GMSD against the golden vectors of reference/gmsd.md: the CPU double path to 1e-12,
// the float paths (CPU and Vulkan on lavapipe) to 1e-6 relative.
#include <catch2/catch.hpp>

#include "cpu/gmsd.h"
#include "engine.h"
#include "support.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

using namespace uvpress::engine;

namespace {

struct Golden {
  const char* name;
  uint32_t rows, cols;
  std::function<double(int, int)> y1, y2;
  double gmsd;
};

std::vector<Golden> goldens() {
  auto a1 = [](int i, int j) { return double((37 * i + 11 * j) % 256); };
  auto b1 = [](int i, int j) { return double((i * i + 3 * j * j + i * j) % 256); };
  auto g = [](int i, int j) { return ((i / 4 + j / 4) % 2) ? 255.0 : 0.0; };
  return {
      {"A", 8, 8, a1, [=](int i, int j) { return a1(i, j) + ((i * j) % 5) * 3; }, 0.0004363033361767078},
      {"B", 64, 64, b1, [=](int i, int j) { return b1(i, j) + (i + 2 * j) % 7; }, 0.0003593346462444784},
      {"C", 7, 9, [](int i, int j) { return double((5 * i + 3 * j * j) % 50); },
       [](int i, int j) { return double((5 * i + 3 * j * j) % 50) + (i * j) % 3; }, 0.0002964911389793238},
      {"D", 8, 8, a1, a1, 0.0},
      {"E", 8, 8, [](int, int) { return 100.0; }, [](int, int) { return 200.0; }, 0.08912707141405846},
      {"F", 64, 64, b1, [](int i, int j) { return double(((i * i + 3 * j * j + i * j) * 7 + 13) % 256); },
       0.2235797051047442},
      {"G", 16, 16, g, [=](int i, int j) { return g(i + 1, j + 1); }, 0.4233615434578903},
  };
}

// Row-major (i = row = y, j = column = x), scaled to [0,1].
template <class Real>
std::vector<Real> image(const Golden& c, const std::function<double(int, int)>& f) {
  std::vector<Real> out(size_t(c.rows) * c.cols);
  for (uint32_t i = 0; i < c.rows; ++i)
    for (uint32_t j = 0; j < c.cols; ++j) out[size_t(i) * c.cols + j] = Real(f(int(i), int(j)) / 255.0);
  return out;
}

}  // namespace

TEST_CASE("GMSD golden vectors: CPU double within 1e-12", "[engine][gmsd]") {
  for (const auto& c : goldens()) {
    INFO("case " << c.name);
    auto a = image<double>(c, c.y1), b = image<double>(c, c.y2);
    CHECK(std::abs(cpu::gmsd<double>(a.data(), b.data(), c.cols, c.rows) - c.gmsd) < 1e-12);
    CHECK(std::abs(cpu::gmsd<double>(b.data(), a.data(), c.cols, c.rows) - c.gmsd) < 1e-12);  // symmetric
  }
}

TEST_CASE("GMSD in float of an eval-sized view stays within 0.2 % of the double reference", "[engine][gmsd]") {
  // eval scores 1696 x 1696 views: 719,104 similarity values, nearly all near 1. One float
  // sum over them all drifts (each addition rounds at the running total's magnitude): it
  // put this pair's GMSD 13 % above the double reference. Interleaved lanes (gmsd_sum) keep
  // it within 0.07 %.
  const uint32_t w = 1696, h = 1696;
  std::vector<float> a(size_t(w) * h), b(a.size());
  std::vector<double> ad(a.size()), bd(a.size());
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (size_t i = 0; i < a.size(); ++i) {
    const float x = ((i / w) % 200 < 100 ? 0.3f : 0.7f) + 0.05f * u(rng);  // bars and grain
    a[i] = x, b[i] = std::min(1.0f, x + 0.02f * (u(rng) - 0.5f));
    ad[i] = a[i], bd[i] = b[i];
  }
  const double exact = cpu::gmsd<double>(ad.data(), bd.data(), w, h);
  const double in_float = cpu::gmsd<float>(a.data(), b.data(), w, h);
  INFO("double " << exact << ", float " << in_float);
  REQUIRE(exact > 1e-3);
  CHECK(std::abs(in_float - exact) <= 2e-3 * exact);
}

TEST_CASE("GMSD golden vectors: float paths within 1e-6 relative, CPU and Vulkan", "[engine][gmsd][vulkan]") {
  UVPRESS_LAVAPIPE_OR_SKIP(vk);
  auto cpu_engine = make_cpu_engine({});
  for (const auto& c : goldens()) {
    INFO("case " << c.name);
    auto a = image<float>(c, c.y1), b = image<float>(c, c.y2);
    // Three copies per batch: every pair of a batch is scored alike.
    std::vector<float> aa, bb;
    for (int k = 0; k < 3; ++k) aa.insert(aa.end(), a.begin(), a.end()), bb.insert(bb.end(), b.begin(), b.end());
    ImagePairs pairs{c.cols, c.rows, 3, aa.data(), bb.data()};
    for (Engine* e : {cpu_engine.get(), vk.get()}) {
      INFO(e->device().backend);
      auto g = e->gmsd(pairs);
      for (float v : g) CHECK(std::abs(v - c.gmsd) <= 1e-6 * c.gmsd + 1e-7);
    }
  }
  CHECK(vk->validation_errors() == 0);
}

TEST_CASE("GMSD of images larger than a view: every backend, the CPU reference's bits", "[engine][gmsd][vulkan]") {
  // eval scores its 512-2048 px views through Engine::gmsd: gmsd.comp holds one image per
  // workgroup (64 x 64 at most), so the Vulkan backend scores larger ones on the host with
  // the CPU reference - the same bits, whichever backend eval runs on.
  UVPRESS_LAVAPIPE_OR_SKIP(vk);
  auto cpu_engine = make_cpu_engine({});
  const uint32_t w = 150, h = 97, count = 5;
  std::vector<float> a(size_t(w) * h * count), b(a.size());
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (size_t i = 0; i < a.size(); ++i) a[i] = u(rng), b[i] = std::clamp(a[i] + 0.2f * (u(rng) - 0.5f), 0.0f, 1.0f);
  const ImagePairs pairs{w, h, count, a.data(), b.data()};
  const auto reference = cpu_engine->gmsd(pairs);
  const auto on_vulkan = vk->gmsd(pairs);
  REQUIRE(on_vulkan.size() == count);
  for (uint32_t k = 0; k < count; ++k) {
    CHECK(reference[k] == cpu::gmsd<float>(a.data() + k * w * h, b.data() + k * w * h, w, h));
    CHECK(on_vulkan[k] == reference[k]);
    CHECK(reference[k] > 0.01f);  // the noise is scored
  }
  CHECK(vk->validation_errors() == 0);
}

TEST_CASE("GMSD of pairs of their own sizes: each pair as if scored alone, on every backend", "[engine][gmsd][vulkan]") {
  // eval's views cropped to the asset differ in size: one call scores them all, pair k of
  // sizes[2k] x sizes[2k + 1], the same bits as the pair alone.
  auto cpu_engine = make_cpu_engine({});
  const std::vector<uint32_t> sizes = {150, 97, 33, 70, 64, 64, 201, 18};
  size_t total = 0;
  for (size_t k = 0; k < sizes.size(); k += 2) total += size_t(sizes[k]) * sizes[k + 1];
  std::vector<float> a(total), b(total);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (size_t i = 0; i < a.size(); ++i) a[i] = u(rng), b[i] = std::clamp(a[i] + 0.3f * (u(rng) - 0.5f), 0.0f, 1.0f);
  ImagePairs pairs{0, 0, uint32_t(sizes.size() / 2), a.data(), b.data()};
  pairs.sizes = sizes.data();
  const auto together = cpu_engine->gmsd(pairs);
  REQUIRE(together.size() == sizes.size() / 2);
  size_t at = 0;
  for (uint32_t k = 0; k < pairs.count; ++k) {
    const uint32_t w = sizes[2 * k], h = sizes[2 * k + 1];
    const auto alone = cpu_engine->gmsd(ImagePairs{w, h, 1, a.data() + at, b.data() + at});
    CHECK(together[k] == alone[0]);
    CHECK(together[k] > 0.01f);
    at += size_t(w) * h;
  }
  UVPRESS_LAVAPIPE_OR_SKIP(vk);
  const auto on_vulkan = vk->gmsd(pairs);
  REQUIRE(on_vulkan.size() == together.size());
  for (size_t k = 0; k < together.size(); ++k) CHECK(on_vulkan[k] == together[k]);
  CHECK(vk->validation_errors() == 0);
}

TEST_CASE("GMSD against prepared references: gmsd()'s bits for every size, on every backend", "[engine][gmsd][vulkan]") {
  // eval keeps its reference views as their gradient magnitudes (Engine::gmsd_references)
  // and scores every render against them (Engine::gmsd_against): the same value, bit for
  // bit, as gmsd() of the pair, at odd sizes, at sizes too small to score (n < 2: 0), for
  // pairs of their own sizes and of one size, and for the golden vectors.
  auto cpu_engine = make_cpu_engine({});
  const std::vector<uint32_t> sizes = {150, 97, 33, 70, 1, 1, 2, 3, 64, 64, 201, 18, 5, 1};
  size_t total = 0, half = 0;
  for (size_t k = 0; k < sizes.size(); k += 2)
    total += size_t(sizes[k]) * sizes[k + 1], half += Engine::gmsd_half_size(sizes[k], sizes[k + 1]);
  std::vector<float> a(total), b(total);
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (size_t i = 0; i < a.size(); ++i) a[i] = u(rng), b[i] = std::clamp(a[i] + 0.3f * (u(rng) - 0.5f), 0.0f, 1.0f);
  ImagePairs pairs{0, 0, uint32_t(sizes.size() / 2), a.data(), b.data()};
  pairs.sizes = sizes.data();
  const auto direct = cpu_engine->gmsd(pairs);
  std::vector<float> magnitudes(half, -1.0f);
  cpu_engine->gmsd_references(pairs, magnitudes.data());
  CHECK(std::count(magnitudes.begin(), magnitudes.end(), -1.0f) == 0);  // every element written
  ImagePairs against = pairs;
  against.first = magnitudes.data();
  const auto prepared = cpu_engine->gmsd_against(against);
  REQUIRE(prepared.size() == direct.size());
  for (size_t k = 0; k < direct.size(); ++k) {
    INFO("pair " << k << ": " << sizes[2 * k] << " x " << sizes[2 * k + 1] << ", gmsd " << direct[k]);
    CHECK(prepared[k] == direct[k]);
    // 1 x 1 has one half-size element: 0; the others score their noise.
    CHECK((sizes[2 * k] * sizes[2 * k + 1] == 1 ? direct[k] == 0.0f : direct[k] > 0.0f));
  }
  // One size for the whole call.
  const ImagePairs same{150, 97, 1, a.data(), b.data()};
  std::vector<float> m1(Engine::gmsd_half_size(150, 97));
  cpu_engine->gmsd_references(same, m1.data());
  CHECK(cpu_engine->gmsd_against(ImagePairs{150, 97, 1, m1.data(), b.data()})[0] == direct[0]);
  // The golden vectors, float within 1e-6 relative as gmsd() is.
  for (const auto& c : goldens()) {
    INFO("case " << c.name);
    auto ga = image<float>(c, c.y1), gb = image<float>(c, c.y2);
    std::vector<float> gm(Engine::gmsd_half_size(c.cols, c.rows));
    cpu_engine->gmsd_references(ImagePairs{c.cols, c.rows, 1, ga.data(), nullptr}, gm.data());
    const float v = cpu_engine->gmsd_against(ImagePairs{c.cols, c.rows, 1, gm.data(), gb.data()})[0];
    CHECK(std::abs(v - c.gmsd) <= 1e-6 * c.gmsd + 1e-7);
  }
  UVPRESS_LAVAPIPE_OR_SKIP(vk);
  std::vector<float> on_vulkan(half);
  vk->gmsd_references(pairs, on_vulkan.data());
  CHECK(on_vulkan == magnitudes);
  const auto vk_prepared = vk->gmsd_against(against);
  for (size_t k = 0; k < direct.size(); ++k) CHECK(vk_prepared[k] == direct[k]);
  CHECK(vk->validation_errors() == 0);
}
