// uvpress bench luminance: GMSD steps 1-2 (luminance, 2x2 downsample) on every backend.
#include "bench.h"

#include <chrono>
#include <cstdio>
#include <vector>

namespace uvpress::cli {

namespace {

void bench_luminance(const Globals& g, const std::vector<uint32_t>& batches, uint32_t size, int repeats) {
  auto backends = available_backends(g, "luminance");
  for (uint32_t batch : batches) {
    std::vector<uint32_t> pixels(size_t(batch) * size * size);
    uint32_t h = 12345;
    for (auto& p : pixels) p = (h = h * 1664525u + 1013904223u);
    engine::Rgba8Batch in{size, size, batch, pixels.data()};
    double cpu_rate = 0;
    for (auto& b : backends) {
      b.engine->luminance(in);  // warm-up: pipelines, buffers, page faults
      auto t0 = std::chrono::steady_clock::now();
      for (int r = 0; r < repeats; ++r) b.engine->luminance(in);
      double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / repeats;
      double rate = batch / s;
      if (b.label == "cpu") cpu_rate = rate;
      auto d = b.engine->device();
      nlohmann::ordered_json line = {{"bench", "luminance"}, {"backend", d.backend},     {"device", d.name},
                                     {"device_type", d.type}, {"threads", d.threads},     {"batch", batch},
                                     {"size", size},          {"images_per_s", rate},     {"seconds", s},
                                     {"vs_cpu", cpu_rate > 0 ? rate / cpu_rate : 1.0}};
      std::printf("%s\n", line.dump().c_str());
      std::fflush(stdout);
    }
  }
}

}  // namespace

void add_bench_luminance(CLI::App& bench, Globals& g) {
  auto* lum = bench.add_subcommand("luminance", "GMSD luminance + 2x2 downsample on every backend");
  auto batches = std::make_shared<std::vector<uint32_t>>(std::vector<uint32_t>{1000, 10000});
  auto size = std::make_shared<uint32_t>(64);
  auto repeats = std::make_shared<int>(3);
  lum->add_option("--batch", *batches, "Images per batch (several allowed)")->capture_default_str();
  lum->add_option("--size", *size, "Image side in pixels")->capture_default_str()->check(CLI::Range(1u, 4096u));
  lum->add_option("--repeat", *repeats, "Timed repetitions per configuration")->capture_default_str()->check(CLI::Range(1, 1000));
  lum->callback([&g, batches, size, repeats] {
    g.action = [&g, batches, size, repeats] {
      bench_luminance(g, *batches, *size, *repeats);
      return 0;
    };
  });
}

}  // namespace uvpress::cli
