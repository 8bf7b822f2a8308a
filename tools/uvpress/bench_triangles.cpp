// uvpress bench triangles: the triangle stage end to end (views, 100 GP-BO evaluations a
// triangle with the initial design, weights), triangles per second and the host/device
// split, per backend, on the demo asset and on any glTF given with --asset.
#include "bench.h"

#include "core/error.h"
#include "io/asset.h"
#include "io/image_io.h"
#include "perceptual/triangle_stage.h"
#include "pipeline/demo_asset.h"

#include <cstdio>
#include <filesystem>

namespace uvpress::cli {

namespace {

struct Workload {
  std::string name;
  io::Primitive primitive;
  int tex_coord = 0;
  Image texture;
  std::vector<float> luminance;
};

// The first primitive sampling a baseColor texture, with that texture.
Workload load_workload(const std::string& spec) {
  io::GltfFile file = spec == "demo" ? pipeline::make_demo_asset() : io::load_gltf(spec);
  io::Asset asset = io::build_asset(file);
  for (const auto& image : asset.images)
    for (const auto& use : image.uses)
      if (use.role == io::TextureRole::BaseColor && !use.tiled) {
        Workload w;
        w.name = spec == "demo" ? "demo" : std::filesystem::path(spec).stem().string();
        w.primitive = asset.primitives[size_t(use.primitive)];
        w.tex_coord = use.tex_coord;
        w.texture = io::decode_image(file.image_bytes[size_t(image.index)], spec);
        w.luminance = perceptual::luminance_plane(w.texture);
        return w;
      }
  throw InputError(spec, "no primitive samples a baseColor texture");
}

void bench_triangles(const Globals& g, const std::vector<std::string>& assets, uint32_t limit, int evaluations) {
  std::vector<Workload> work;
  for (const auto& a : assets) work.push_back(load_workload(a));
  auto backends = available_backends(g);
  for (const auto& w : work) {
    const io::Primitive& p = w.primitive;
    perceptual::TriangleViewInput in{p.positions.data(), p.vertex_count(), p.indices.data(), p.triangle_count(),
                                     p.uv_sets[size_t(w.tex_coord)].uv.data(), w.texture.width, w.texture.height};
    // An even sample across the mesh when limited.
    std::vector<uint32_t> which;
    const uint32_t n = uint32_t(p.triangle_count());
    const uint32_t take = limit ? std::min(limit, n) : n;
    for (uint32_t k = 0; k < take; ++k) which.push_back(uint32_t(uint64_t(k) * n / take));
    perceptual::TriangleStageOptions o;
    o.evaluations = evaluations;
    o.early_stop = false;  // the benchmark's figure is per 100 evaluations
    for (auto& b : backends) {
      perceptual::TriangleStageStats stats;
      auto results = perceptual::optimize_triangles(*b.engine, in, w.luminance, o, which, &stats);
      size_t feasible = 0;
      for (auto& r : results) feasible += r.gmsd < o.epsilon;
      auto d = b.engine->device();
      nlohmann::ordered_json line = {{"bench", "triangles"},
                                     {"asset", w.name},
                                     {"backend", d.backend},
                                     {"device", d.name},
                                     {"triangles", results.size()},
                                     {"mesh_triangles", n},
                                     {"evals_per_triangle", evaluations},
                                     {"triangles_per_s", double(results.size()) / stats.wall_seconds},
                                     {"wall_s", stats.wall_seconds},
                                     {"host_s", stats.host_seconds},
                                     {"device_s", stats.device_seconds},
                                     {"evaluations", stats.evaluations},
                                     {"rounds", stats.rounds},
                                     {"feasible", feasible}};
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
  cmd->add_option("--asset", *assets, "'demo' or a glTF file (several allowed)")->capture_default_str();
  cmd->add_option("--triangles", *limit, "Triangles per asset, spread evenly (0: all)")->capture_default_str();
  cmd->add_option("--evaluations", *evaluations, "Evaluations per triangle")->capture_default_str()->check(CLI::Range(11, 1000));
  cmd->callback([&g, assets, limit, evaluations] {
    g.action = [&g, assets, limit, evaluations] {
      bench_triangles(g, *assets, *limit, *evaluations);
      return 0;
    };
  });
}

}  // namespace uvpress::cli
