// uvpress bench views: candidates per second for render + least-squares bake + GMSD of
// per-triangle views, on every backend, on the views reparam makes of an asset (the demo
// asset by default, or --asset: every triangle of each textured primitive, so the views'
// sizes are that asset's), batch sizes 1K / 10K / 50K by default.
#include "bench.h"

#include "perceptual/triangle_view.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

namespace uvpress::cli {

namespace {

// One line per backend and batch for the views of one textured primitive.
void bench_part(const Globals& g, const std::string& name, size_t part, const TexturedPart& w,
                const std::vector<uint32_t>& batches, uint32_t size, int repeats) {
  const io::Primitive& p = w.primitive;
  perceptual::TriangleViewInput in{p.positions.data(), p.vertex_count(), p.indices.data(), p.triangle_count(),
                                   p.uv_sets[size_t(w.tex_coord)].uv.data(), w.texture.width, w.texture.height};
  engine::ViewSetDesc desc = perceptual::make_triangle_views(in, size).desc;
  desc.texture = w.luminance.data(), desc.texture_width = w.texture.width, desc.texture_height = w.texture.height;

  // Candidates as the triangle stage draws them: lambda in (0, 1], alpha, beta in [0, pi/2).
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> lambda(0.05f, 1.0f), angle(0.0f, 1.5707963f);
  uint32_t largest = 0;
  for (uint32_t b : batches) largest = std::max(largest, b);
  std::vector<engine::ViewCandidate> all(largest);
  for (uint32_t k = 0; k < largest; ++k) {
    float l1 = lambda(rng), l2 = lambda(rng), a = angle(rng), b = angle(rng);
    float ca = std::cos(a), sa = std::sin(a), cb = std::cos(b), sb = std::sin(b);
    // J = R(a) V(b) diag(l1, l2) V(b)^T
    float m00 = cb * cb * l1 + sb * sb * l2, m01 = cb * sb * (l1 - l2), m11 = sb * sb * l1 + cb * cb * l2;
    all[k] = {{ca * m00 - sa * m01, ca * m01 - sa * m11, sa * m00 + ca * m01, sa * m01 + ca * m11},
              k % uint32_t(desc.views.size()), 0, 0, 0};
  }

  auto backends = available_backends(g, "views");
  std::vector<double> cpu_rate(batches.size(), 0.0);  // the CPU backend runs first
  for (auto& b : backends) {
    auto t0 = std::chrono::steady_clock::now();
    auto views = b.engine->prepare_views(desc);
    double prepare_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::vector<float> out(largest);
    b.engine->score_views(*views, all.data(), std::min<size_t>(256, all.size()), out.data());  // warm-up
    for (size_t bi = 0; bi < batches.size(); ++bi) {
      const uint32_t batch = batches[bi];
      t0 = std::chrono::steady_clock::now();
      for (int r = 0; r < repeats; ++r) b.engine->score_views(*views, all.data(), batch, out.data());
      double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / repeats;
      auto d = b.engine->device();
      const double rate = batch / s;
      if (d.backend == "cpu") cpu_rate[bi] = rate;
      nlohmann::ordered_json line = {{"bench", "views"},
                                     {"backend", d.backend},
                                     {"device", d.name},
                                     {"device_type", d.type},
                                     {"threads", d.threads},
                                     {"asset", name},
                                     {"part", part},
                                     {"views", desc.views.size()},
                                     {"batch", batch},
                                     {"size", size},
                                     {"views_per_s", rate},
                                     {"vs_cpu", cpu_rate[bi] > 0 ? rate / cpu_rate[bi] : 1.0},
                                     {"seconds", s},
                                     {"prepare_views_per_s", desc.views.size() / prepare_s}};
      std::printf("%s\n", line.dump().c_str());
      std::fflush(stdout);
    }
  }
}

void bench_views(const Globals& g, const std::string& spec, const std::vector<uint32_t>& batches, uint32_t size,
                 int repeats) {
  const TexturedAsset asset = load_textured_asset(spec);
  for (size_t part = 0; part < asset.parts.size(); ++part)
    bench_part(g, asset.name, part, asset.parts[part], batches, size, repeats);
}

}  // namespace

void add_bench_views(CLI::App& bench, Globals& g) {
  auto* cmd = bench.add_subcommand("views", "Per-triangle views: render + least-squares bake + GMSD on every backend");
  auto batches = std::make_shared<std::vector<uint32_t>>(std::vector<uint32_t>{1000, 10000, 50000});
  auto size = std::make_shared<uint32_t>(64);
  auto repeats = std::make_shared<int>(1);
  auto asset = std::make_shared<std::string>("demo");
  cmd->add_option("--asset", *asset, "'demo' or a glTF file: the views of every triangle of each textured primitive")
      ->capture_default_str();
  cmd->add_option("--batch", *batches, "Candidates per batch (several allowed)")->capture_default_str();
  cmd->add_option("--size", *size, "View side in pixels (even, 8..64)")->capture_default_str()->check(CLI::Range(8u, 64u));
  cmd->add_option("--repeat", *repeats, "Timed repetitions per configuration")->capture_default_str()->check(CLI::Range(1, 100));
  cmd->callback([&g, asset, batches, size, repeats] {
    g.action = [&g, asset, batches, size, repeats] {
      bench_views(g, *asset, *batches, *size, *repeats);
      return 0;
    };
  });
}

}  // namespace uvpress::cli
