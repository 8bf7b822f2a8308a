// uvpress bench rebake: seconds to re-bake a 2048 x 2048 RGBA colour texture (sRGB, alpha:
// linear light, premultiplied) into a packed layout at half the texels, on every backend,
// one JSON line per backend. The layout: 8 x 8 charts of 128 triangles each, moved to
// shuffled cells, turned by multiples of 90 degrees and shrunk to leave gutters, as the
// packer leaves them. "seconds" is the whole atlas::rebake (host set-up, owners, sampling,
// conversions, gutter fill); "sampling_s" the engine's rebake_texels alone.
#include "bench.h"

#include "atlas/rebake.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>

namespace uvpress::cli {

namespace {

struct BenchLayout {
  std::vector<uint32_t> idx;
  std::vector<float> old_uv, new_uv;
};

BenchLayout bench_layout(int charts, int grid) {
  BenchLayout L;
  std::mt19937 rng(1);
  std::vector<int> cell(size_t(charts) * charts);
  std::iota(cell.begin(), cell.end(), 0);
  std::shuffle(cell.begin(), cell.end(), rng);
  for (int c = 0; c < charts * charts; ++c) {
    const int oi = c % charts, oj = c / charts, ni = cell[size_t(c)] % charts, nj = cell[size_t(c)] / charts;
    const int turn = int(rng() % 4);
    const uint32_t base = uint32_t(L.old_uv.size() / 2);
    for (int j = 0; j <= grid; ++j)
      for (int i = 0; i <= grid; ++i) {
        const double s = double(i) / grid, t = double(j) / grid;
        L.old_uv.push_back(float((oi + s) / charts));
        L.old_uv.push_back(float((oj + t) / charts));
        double a = s - 0.5, b = t - 0.5;
        for (int k = 0; k < turn; ++k) std::swap(a, b), a = -a;
        L.new_uv.push_back(float((ni + 0.5 + 0.92 * a) / charts));
        L.new_uv.push_back(float((nj + 0.5 + 0.92 * b) / charts));
      }
    for (int j = 0; j < grid; ++j)
      for (int i = 0; i < grid; ++i) {
        const uint32_t v = base + uint32_t(j * (grid + 1) + i), w = uint32_t(grid + 1);
        L.idx.insert(L.idx.end(), {v, v + 1, v + w + 1, v, v + w + 1, v + w});
      }
  }
  return L;
}

void bench_rebake(const Globals& g, uint32_t size, uint32_t out_size, int repeats) {
  Image src;
  src.width = src.height = size, src.channels = 4, src.bits = 8;
  src.pixels.resize(size_t(size) * size * 4);
  uint32_t h = 12345;
  for (size_t i = 0; i < src.pixels.size(); ++i) {
    h = h * 1664525u + 1013904223u;
    src.pixels[i] = float((h >> 24) & 0xffu) / 255.0f;
  }
  const BenchLayout L = bench_layout(8, 8);
  const atlas::RebakeMesh mesh{L.idx.data(), L.idx.size(), L.old_uv.data(), L.new_uv.data(), L.old_uv.size() / 2};
  atlas::RebakeOptions o;
  o.width = o.height = out_size;
  o.role = atlas::RebakeRole::Color;
  for (auto& b : available_backends(g)) {
    atlas::RebakeStats stats;
    atlas::rebake(src, {mesh}, o, &stats, b.engine.get());  // warm-up: pipelines, buffers, page faults
    double best = 1e300, best_sampling = 1e300;
    for (int r = 0; r < repeats; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      atlas::rebake(src, {mesh}, o, &stats, b.engine.get());
      best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      best_sampling = std::min(best_sampling, stats.sample_seconds);
    }
    const auto d = b.engine->device();
    nlohmann::ordered_json line = {{"bench", "rebake"},       {"backend", d.backend},
                                   {"device", d.name},        {"device_type", d.type},
                                   {"threads", d.threads},    {"size", size},
                                   {"out_size", out_size},    {"channels", 4},
                                   {"triangles", stats.triangles}, {"covered", stats.covered},
                                   {"seconds", best},         {"sampling_s", best_sampling}};
    std::printf("%s\n", line.dump().c_str());
    std::fflush(stdout);
  }
}

}  // namespace

void add_bench_rebake(CLI::App& bench, Globals& g) {
  auto* cmd = bench.add_subcommand("rebake", "Seconds to re-bake a 2048^2 RGBA texture per backend");
  auto size = std::make_shared<uint32_t>(2048);
  auto out_size = std::make_shared<uint32_t>(1448);
  auto repeats = std::make_shared<int>(3);
  cmd->add_option("--size", *size, "Source texture, texels a side")->capture_default_str()->check(CLI::Range(16u, 8192u));
  cmd->add_option("--out-size", *out_size, "New texture, texels a side (1448: half the texels)")
      ->capture_default_str()
      ->check(CLI::Range(16u, 8192u));
  cmd->add_option("--repeat", *repeats, "Timed repetitions (the best is reported)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  cmd->callback([&g, size, out_size, repeats] {
    g.action = [&g, size, out_size, repeats] {
      bench_rebake(g, *size, *out_size, *repeats);
      return 0;
    };
  });
}

}  // namespace uvpress::cli
