// The `uvpress bench` family: each benchmark prints one JSON line per configuration on
// stdout (figures, device, sizes) and compares variants as ratios within one run.
#pragma once

#include "cli.h"

#include <string>
#include <utility>
#include <vector>

namespace uvpress::cli {

struct Backend {
  std::string label;  // "cpu" or "vulkan"
  std::unique_ptr<engine::Engine> engine;
};

// Every backend this machine has (the native CPU one, then each Vulkan kind present), or
// only the one --device names when it names one. Each Vulkan kind that is absent gets its
// own line on stdout, {"bench": bench, "backend": "vulkan", "device": "gpu" | "lavapipe",
// "skipped": why}, so a run says what it did not measure without an error on stderr.
std::vector<Backend> available_backends(const Globals& g, const char* bench);

// The assets the quality benchmarks measure: (name, path; "" = the embedded demo asset):
// the demo and the shared Duck, Fox, CesiumMilkTruck and MultiUVTest under `shared`
// (unless only_given), then each of `extra`.
std::vector<std::pair<std::string, std::string>> bench_assets(const std::string& shared, bool only_given,
                                                              const std::vector<std::string>& extra);

// One file per benchmark; each adds its subcommand under `bench`.
void add_bench_luminance(CLI::App& bench, Globals& g);
void add_bench_views(CLI::App& bench, Globals& g);
void add_bench_triangles(CLI::App& bench, Globals& g);
void add_bench_flatten(CLI::App& bench, Globals& g);
void add_bench_eval(CLI::App& bench, Globals& g);
void add_bench_rebake(CLI::App& bench, Globals& g);
void add_bench_quality(CLI::App& bench, Globals& g);
void add_bench_rebake_lsq(CLI::App& bench, Globals& g);
void add_bench_pack(CLI::App& bench, Globals& g);

}  // namespace uvpress::cli
