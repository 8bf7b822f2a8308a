// Shared by the subcommands of the uvpress CLI: global options, how a command hands its
// work back to main, and the one place where errors become exit codes.
#pragma once

#include "engine.h"
#include "io/astc_codec.h"
#include "io/gltf_io.h"
#include "io/references.h"

#include <CLI/CLI.hpp>

#include "eval/eval.h"
#include <nlohmann/json.hpp>

#include <chrono>
#include <functional>
#include <memory>
#include <string>

namespace uvpress::pipeline {
struct ReparamOptions;
}

namespace uvpress::cli {

struct Globals {
  bool verbose = false;
  std::string device = "auto";  // --device, else UVPRESS_DEVICE, else auto
  std::string report;           // --report FILE.json
  bool validation = false;      // --vulkan-validation, or UVPRESS_VALIDATION=1
  bool allow_outside_refs = false;  // --allow-outside-refs: trusted layouts only
  bool strict = false;              // --strict: refuse inputs that break the glTF rules checked on load
  std::function<int()> action;  // set by the chosen subcommand's callback

  // The engine for --device; prints the choice in verbose mode.
  std::unique_ptr<engine::Engine> make_engine() const;
  // What an input's buffer and image URIs may name (every load_gltf takes it).
  io::RefPolicy refs() const { return {allow_outside_refs}; }
  // A glTF input: io::load_gltf under refs(), then the Khronos rules that matter here
  // (io/gltf_rules.h). An input that breaks them is one warning line with the count (the
  // output keeps what it does not touch), or with --strict an InputError. `checked`, when
  // given, receives the report's {"errors": n, "codes": {code: n}}.
  io::GltfFile load_input(const std::string& path, nlohmann::ordered_json* checked = nullptr) const;
  // Before any work: every output file (and --report) and output folder created-for and
  // checked writable (io::prepare_output_file / prepare_output_folder). Throws InputError.
  void prepare_outputs(const std::vector<std::string>& files, const std::vector<std::string>& folders = {}) const;
  // Writes `report` atomically when --report was given.
  void write_report(const nlohmann::ordered_json& report) const;
  // Staged with the asset in `writer` (committed by the caller with it): a report that
  // cannot be written leaves no asset.
  void write_report(const nlohmann::ordered_json& report, io::AtomicWriter& writer) const;
  // "-v" stage timing: prints "stage: 12.3 ms" (the time since `since`) on stderr and
  // restarts `since` for the next stage.
  void stage(const char* name, std::chrono::steady_clock::time_point& since) const;
};

void add_info(CLI::App& app, Globals& g);
void add_reparam(CLI::App& app, Globals& g);
void add_copy(CLI::App& app, Globals& g);
void add_demo(CLI::App& app, Globals& g);
void add_bench(CLI::App& app, Globals& g);
void add_flatten(CLI::App& app, Globals& g);
void add_eval(CLI::App& app, Globals& g);
void add_batch(CLI::App& app, Globals& g);

// Checks one --cost-grid value: a number in (0, 4] (usage error otherwise).
CLI::Validator cost_grid_value();
// eval's view options on `cmd`: PREFIXresolution auto|N (0 = auto) and PREFIXfilter
// trilinear|bilinear (prefix "--" for eval and the benches, "--eval-" for batch's eval,
// "--score-" for the views reparam scores its candidates and guard with).
void add_view_options(CLI::App* cmd, uint32_t& resolution, eval::TextureFilter& filter, const std::string& prefix);
// eval's shading on `cmd`: PREFIXshading auto|unlit|lit (prefixes as above).
void add_shading_option(CLI::App* cmd, eval::Shading& shading, const std::string& prefix);
// reparam's --keep-aspect and --gutter on `cmd` (reparam, batch, bench pack): one text each.
void add_keep_aspect_option(CLI::App* cmd, bool& keep_aspect);
void add_gutter_option(CLI::App* cmd, uint32_t& gutter);
// Every option of reparam's layout and bake on `cmd` (reparam and batch: the same names,
// texts and checks): cost, scoring views, packing, triangle stage, candidates and guard.
// Returns --block-align, whose presence block_alignment() needs.
CLI::Option* add_reparam_options(CLI::App* cmd, pipeline::ReparamOptions& o);

// GPU-ready copies of the written textures (gpu_output.cpp): --texture-format source|astc,
// --astc-block WxH, --astc-quality Q.
struct GpuOutputArgs {
  std::string format = "source";
  io::AstcOptions astc;
  bool block_given = false;  // --astc-block was given
};
void add_gpu_output_options(CLI::App* cmd, GpuOutputArgs& args);
// With --texture-format astc and a square block: the chart alignment it needs (an
// explicit --block-align wins); else `block` unchanged.
uint32_t block_alignment(const GpuOutputArgs& args, uint32_t block, bool block_align_given);
// With --texture-format astc: every image of `file` encoded as an ASTC KTX2 copy (written
// beside the output by save_gltf); the report's `gpu_textures` [{image, name, format,
// vk_format, quality, size, levels, bytes, rmse_8bit, psnr_db, seconds}] and, in
// `summary`, the summary line's words. Otherwise null, and nothing changes.
nlohmann::ordered_json attach_gpu_textures(io::GltfFile& file, const GpuOutputArgs& args, std::string* summary);

// "1.2 MB"-style size for summary lines.
std::string human_bytes(uint64_t bytes);

}  // namespace uvpress::cli
