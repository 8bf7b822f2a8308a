// uvpress bench triangles: the triangle stage end to end (views, 100 GP-BO evaluations a
// triangle with the initial design, weights), triangles per second and the host/device
// split, per backend, on the demo asset and on any glTF given with --asset.
#include "bench.h"

#include "core/quantile.h"
#include "perceptual/triangle_stage.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace uvpress::cli {

namespace {

// Standard deviation of the source luminance over a triangle (bilinear samples at 66
// barycentric grid points): a triangle is "detailed" when it is at least kDetailed.
constexpr double kDetailed = 0.02;
double luminance_spread(const perceptual::TriangleViewInput& in, const std::vector<float>& lum, uint32_t t) {
  const uint32_t* f = &in.indices[3 * t];
  const double W = in.texture_width, H = in.texture_height;
  auto sample = [&](double s, double tt) {
    s = std::clamp(s, 0.0, W - 1), tt = std::clamp(tt, 0.0, H - 1);
    const size_t i0 = size_t(s), j0 = size_t(tt), i1 = std::min(i0 + 1, size_t(W) - 1), j1 = std::min(j0 + 1, size_t(H) - 1);
    const double a = s - double(i0), b = tt - double(j0);
    const size_t w = in.texture_width;
    return (1 - b) * ((1 - a) * lum[j0 * w + i0] + a * lum[j0 * w + i1]) + b * ((1 - a) * lum[j1 * w + i0] + a * lum[j1 * w + i1]);
  };
  const int n = 10;
  double sum = 0, sum2 = 0;
  int count = 0;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j) {
      const double l1 = double(i) / n, l2 = double(j) / n, l0 = 1 - l1 - l2;
      double s = 0, tt = 0;
      const double l[3] = {l0, l1, l2};
      for (int k = 0; k < 3; ++k) s += l[k] * (in.uvs[2 * f[k]] * W - 0.5), tt += l[k] * (in.uvs[2 * f[k] + 1] * H - 0.5);
      const double y = sample(s, tt);
      sum += y, sum2 += y * y, ++count;
    }
  const double mean = sum / count;
  return std::sqrt(std::max(0.0, sum2 / count - mean * mean));
}

void bench_triangles(const Globals& g, const std::vector<std::string>& specs, uint32_t limit, int evaluations,
                     bool early_stop) {
  std::vector<TexturedAsset> work;
  for (const auto& a : specs) work.push_back(load_textured_asset(a));
  auto backends = available_backends(g, "triangles");
  for (const auto& a : work) {
    size_t total = 0;
    for (const auto& w : a.parts) total += w.primitive.triangle_count();
    const size_t take = limit ? std::min<size_t>(limit, total) : total;
    for (auto& b : backends) {
      perceptual::TriangleStageOptions o;  // what reparam runs by default
      o.evaluations = evaluations;
      o.early_stop = early_stop;
      perceptual::TriangleStageStats sum;
      size_t triangles = 0, identity_lossless = 0, resolved = 0, complete = 0, feasible = 0, coarse = 0, views = 0;
      size_t evals = 0;
      std::vector<double> shrink_cost, shrink_cost_detailed, lambda_area;
      size_t first = 0;  // of the current part, in the asset's triangle order
      for (const auto& w : a.parts) {
        const io::Primitive& p = w.primitive;
        const size_t n = p.triangle_count();
        // An even sample across all of the asset's triangles when limited.
        std::vector<uint32_t> which;
        for (size_t k = 0; k < take; ++k) {
          const size_t t = k * total / take;
          if (t >= first && t < first + n) which.push_back(uint32_t(t - first));
        }
        first += n;
        if (which.empty()) continue;
        perceptual::TriangleViewInput in{p.positions.data(), p.vertex_count(), p.indices.data(), p.triangle_count(),
                                         p.uv_sets[size_t(w.tex_coord)].uv.data(), w.texture.width, w.texture.height};
        perceptual::TriangleStageStats stats;
        auto results = perceptual::optimize_triangles(*b.engine, in, w.luminance, o, which, &stats);
        auto half = perceptual::measure_triangles(*b.engine, in, w.luminance, o, {0.5, 0, 0, 0.5}, which);
        sum.wall_seconds += stats.wall_seconds, sum.host_seconds += stats.host_seconds;
        sum.device_seconds += stats.device_seconds, sum.evaluations += stats.evaluations;
        sum.view_scores += stats.view_scores, sum.rounds += stats.rounds;
        for (size_t k = 0; k < results.size(); ++k) {
          const auto& r = results[k];
          ++triangles;
          identity_lossless += r.identity_gmsd < 1e-3;
          resolved += r.texels_per_pixel <= 1.0 + 1e-6;
          complete += r.complete;
          feasible += r.feasible && r.gmsd < o.epsilon;  // from the loss measured at the returned J
          coarse += r.identity_lattice > 1;
          views += size_t(r.views);
          evals += size_t(r.evaluations);
          shrink_cost.push_back(half[k] - r.identity_gmsd);
          if (luminance_spread(in, w.luminance, which[k]) >= kDetailed) shrink_cost_detailed.push_back(half[k] - r.identity_gmsd);
          lambda_area.push_back(r.lambda1 * r.lambda2);
        }
      }
      auto d = b.engine->device();
      const double T = double(std::max<size_t>(triangles, 1));
      nlohmann::ordered_json line = {{"bench", "triangles"},
                                     {"asset", a.name},
                                     {"backend", d.backend},
                                     {"device", d.name},
                                     {"triangles", triangles},
                                     {"mesh_triangles", total},
                                     {"evals_per_triangle", double(evals) / T},
                                     {"early_stop", early_stop},
                                     {"triangles_per_s", double(triangles) / std::max(sum.wall_seconds, 1e-9)},
                                     {"wall_s", sum.wall_seconds},
                                     {"host_s", sum.host_seconds},
                                     {"device_s", sum.device_seconds},
                                     {"views_per_triangle", double(views) / T},
                                     {"view_scores", sum.view_scores},
                                     {"identity_lossless", double(identity_lossless) / T},
                                     {"views_resolve_texels", double(resolved) / T},
                                     {"triangles_fully_viewed", double(complete) / T},
                                     {"tiles_coarsened", double(coarse) / T},
                                     {"feasible", double(feasible) / T},
                                     {"shrink_cost_p50", quantile(shrink_cost, 0.5)},
                                     {"shrink_cost_p75", quantile(shrink_cost, 0.75)},
                                     {"detailed", double(shrink_cost_detailed.size()) / T},
                                     {"shrink_cost_detailed_median", quantile(shrink_cost_detailed, 0.5)},
                                     {"lambda_area_quartiles",
                                      {quantile(lambda_area, 0.25), quantile(lambda_area, 0.5), quantile(lambda_area, 0.75)}}};
      std::printf("%s\n", line.dump().c_str());
      std::fflush(stdout);
    }
  }
}

}  // namespace

void add_bench_triangles(CLI::App& bench, Globals& g) {
  auto* cmd = bench.add_subcommand("triangles", "Triangle stage (GP-BO, 100 evaluations a triangle) on every backend");
  auto assets = std::make_shared<std::vector<std::string>>(std::vector<std::string>{"demo"});
  auto limit = std::make_shared<uint32_t>(1024);
  auto evaluations = std::make_shared<int>(100);
  auto early_stop = std::make_shared<bool>(perceptual::TriangleStageOptions{}.early_stop);
  cmd->add_option("--asset", *assets, "'demo' or a glTF file (several allowed)")->capture_default_str();
  cmd->add_option("--triangles", *limit, "Triangles per asset over every textured primitive, spread evenly (0: all)")->capture_default_str();
  cmd->add_option("--evaluations", *evaluations, "Evaluations per triangle")->capture_default_str()->check(CLI::Range(11, 1000));
  cmd->add_flag("--early-stop,!--no-early-stop", *early_stop,
                "Stop a triangle's search when it stalls (reparam's default); --no-early-stop spends every evaluation");
  cmd->callback([&g, assets, limit, evaluations, early_stop] {
    g.action = [&g, assets, limit, evaluations, early_stop] {
      bench_triangles(g, *assets, *limit, *evaluations, *early_stop);
      return 0;
    };
  });
}

}  // namespace uvpress::cli
