// uvpress bench <name>: the parent command and what the benchmarks share.
#include "bench.h"

#include "core/error.h"
#include "io/gltf_io.h"
#include "io/image_io.h"
#include "pipeline/demo_asset.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>

namespace uvpress::cli {

std::vector<Backend> available_backends(const Globals& g, const char* bench) {
  std::vector<Backend> out;
  if (g.device != "auto") {
    auto e = g.make_engine();
    out.push_back({e->device().backend, std::move(e)});
    return out;
  }
  engine::EngineOptions options;
  options.validation = g.validation;
  out.push_back({"cpu", engine::make_cpu_engine(options)});
  for (auto request : {engine::DeviceRequest::Gpu, engine::DeviceRequest::Lavapipe}) {
    try {
      out.push_back({"vulkan", engine::make_vulkan_engine(request, options)});
    } catch (const engine::EngineError& e) {
      const nlohmann::ordered_json line = {
          {"bench", bench}, {"backend", "vulkan"}, {"device", engine::to_string(request)}, {"skipped", e.what()}};
      std::printf("%s\n", line.dump().c_str());
      std::fflush(stdout);
    }
  }
  return out;
}

std::vector<std::pair<std::string, std::string>> bench_assets(const std::string& shared, bool only_given,
                                                              const std::vector<std::string>& extra) {
  std::vector<std::pair<std::string, std::string>> inputs;
  if (!only_given) {
    inputs.push_back({"demo", ""});
    for (const char* rel : {"Duck/glTF/Duck.gltf", "Fox/glTF/Fox.gltf", "CesiumMilkTruck/glTF/CesiumMilkTruck.gltf",
                            "MultiUVTest/glTF/MultiUVTest.gltf"})
      inputs.push_back({std::filesystem::path(rel).stem().string(), shared + "/" + rel});
  }
  for (const auto& p : extra) inputs.push_back({std::filesystem::path(p).stem().string(), p});
  return inputs;
}

void add_bench(CLI::App& app, Globals& g) {
  auto* bench = app.add_subcommand("bench", "Benchmarks: one JSON line per configuration on stdout");
  bench->require_subcommand(1);
  add_bench_luminance(*bench, g);
  add_bench_views(*bench, g);
  add_bench_triangles(*bench, g);
  add_bench_flatten(*bench, g);
  add_bench_eval(*bench, g);
  add_bench_rebake(*bench, g);
  add_bench_quality(*bench, g);
  add_bench_rebake_lsq(*bench, g);
  add_bench_pack(*bench, g);
}

TexturedAsset load_textured_asset(const std::string& spec) {
  io::GltfFile file = spec == "demo" ? pipeline::make_demo_asset() : io::load_gltf(spec);
  io::Asset asset = io::build_asset(file);
  TexturedAsset a;
  a.name = spec == "demo" ? "demo" : std::filesystem::path(spec).stem().string();
  std::vector<std::pair<int, int>> seen;
  for (const auto& image : asset.images)
    for (const auto& use : image.uses) {
      if (use.role != io::TextureRole::BaseColor || use.tiled) continue;
      if (std::find(seen.begin(), seen.end(), std::pair{use.primitive, use.tex_coord}) != seen.end()) continue;
      seen.push_back({use.primitive, use.tex_coord});
      TexturedPart w;
      w.primitive = asset.primitives[size_t(use.primitive)];
      w.tex_coord = use.tex_coord;
      w.texture = io::decode_image(file.image_bytes[size_t(image.index)], spec);
      w.luminance = luminance_plane(w.texture);
      a.parts.push_back(std::move(w));
    }
  if (a.parts.empty()) throw InputError(spec, "no primitive samples a baseColor texture");
  return a;
}

}  // namespace uvpress::cli
