// uvpress bench <name>: the parent command and what the benchmarks share.
#include "bench.h"

#include <cstdio>

namespace uvpress::cli {

std::vector<Backend> available_backends(bool validation) {
  std::vector<Backend> out;
  engine::EngineOptions options;
  options.validation = validation;
  out.push_back({"cpu", engine::make_cpu_engine(options)});
  for (auto request : {engine::DeviceRequest::Gpu, engine::DeviceRequest::Lavapipe}) {
    try {
      out.push_back({"vulkan", engine::make_vulkan_engine(request, options)});
    } catch (const engine::EngineError& e) {
      std::fprintf(stderr, "bench: no Vulkan %s device: %s\n", engine::to_string(request), e.what());
    }
  }
  return out;
}

void add_bench(CLI::App& app, Globals& g) {
  auto* bench = app.add_subcommand("bench", "Benchmarks: one JSON line per configuration on stdout");
  bench->require_subcommand(1);
  add_bench_luminance(*bench, g);
  add_bench_flatten(*bench, g);
}

}  // namespace uvpress::cli
