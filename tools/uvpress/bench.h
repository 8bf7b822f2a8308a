// The `uvpress bench` family: each benchmark prints one JSON line per configuration on
// stdout (figures, device, sizes) and compares variants as ratios within one run.
#pragma once

#include "cli.h"

#include "core/image.h"
#include "io/asset.h"

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

// One primitive that samples a baseColor texture (not tiled), with that texture.
struct TexturedPart {
  io::Primitive primitive;
  int tex_coord = 0;
  Image texture;
  std::vector<float> luminance;
};

// An asset's textured primitives: each (primitive, UV set) that a baseColor image samples,
// once. `spec`: "demo" (the embedded demo asset) or a glTF file; name: "demo" or the file's
// stem. Throws InputError when nothing samples a baseColor texture.
struct TexturedAsset {
  std::string name;
  std::vector<TexturedPart> parts;
};
TexturedAsset load_textured_asset(const std::string& spec);

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
