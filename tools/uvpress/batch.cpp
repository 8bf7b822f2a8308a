// uvpress batch --manifest LIST -o DIR [reparam options] [--eval] [--shard-index I
//   --shard-count N] [--jobs N] [--force] [--collect]: reparam (and eval) over every asset a
// manifest lists, resumable, sharded for array jobs (Slurm, Kubernetes, AWS Batch); see
// host/batch/batch.h.
#include "cli.h"

#include "batch/batch.h"
#include "core/error.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <unistd.h>

namespace uvpress::cli {

namespace {

class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

void write_line(const std::string& line) {
  std::string s = line + "\n";
  for (size_t at = 0; at < s.size();) {  // one write per line: workers share stderr
    ssize_t n = ::write(2, s.data() + at, s.size() - at);
    if (n <= 0) break;
    at += size_t(n);
  }
}

// "-" for a figure the row lacks, or null in its report (NaN).
std::string cell(const std::optional<double>& value, const char* format) {
  if (!value || std::isnan(*value)) return "-";
  char buf[48];
  std::snprintf(buf, sizeof buf, format, *value);
  return buf;
}

void print_table(const batch::BatchSummary& summary) {
  size_t w = 5;
  for (const auto& a : summary.assets) w = std::max(w, a.name.size());
  std::printf("%-*s  %-8s  %-9s  %8s  %10s  %19s  %21s  %s\n", int(w), "asset", "status", "written", "seconds", "cost ratio",
              "q / q resize", "size in -> out", "output / error");
  for (const auto& a : summary.assets) {
    const std::string& status = a.status;
    // The whole asset (JSON, buffers, images) before and after.
    std::string size = (a.input_bytes ? human_bytes(*a.input_bytes) : std::string("-")) + " -> " +
                       (a.output_bytes ? human_bytes(*a.output_bytes) : std::string("-"));
    std::string last = status == "ok" || status == "skipped" ? a.output.value_or("") : a.error.value_or("");
    // "untouched": ok, but nothing was re-parameterized (the report's warnings say why).
    const std::string written = a.written.value_or("-");
    const std::string q = a.q ? cell(a.q, "%.3g") + " / " + cell(a.q_resize, "%.3g") : "-";
    std::printf("%-*s  %-8s  %-9s  %8s  %10s  %19s  %21s  %s\n", int(w), a.name.c_str(),
                status == "failed" ? "FAILED" : status.c_str(), written.c_str(), cell(a.seconds, "%.1f").c_str(),
                cell(a.cost_ratio, "%.3f").c_str(), q.c_str(), size.c_str(), last.c_str());
  }
  std::printf("%zu assets: %zu ok, %zu skipped, %zu failed", summary.assets.size(), summary.count("ok"), summary.count("skipped"),
              summary.count("failed") + summary.count("missing") + summary.count("stale"));
  if (!summary.collected) std::printf(" (shard %zu of %zu)", summary.shard_index, summary.shard_count);
  std::printf(" in %.1f s\n", summary.seconds);
}

}  // namespace

void add_batch(CLI::App& app, Globals& g) {
  auto* cmd = app.add_subcommand("batch", "reparam (and eval) over a manifest of assets: resumable, sharded, parallel");
  struct Args {
    batch::BatchOptions o;
    bool collect = false;
    std::vector<double> grid;
    std::optional<size_t> shard_index, shard_count;
    GpuOutputArgs gpu;
    CLI::Option* block_align = nullptr;
  };
  auto a = std::make_shared<Args>();
  auto& o = a->o;
  cmd->add_option("--manifest", o.manifest, "Text file: one asset path a line ('#' comments; relative to the file)")->required();
  cmd->add_option("-o,--output", o.output_dir, "Output folder (created when missing)")->required();
  cmd->add_option("--format", o.format, "Output format of each asset")->capture_default_str()->check(CLI::IsMember({"glb", "gltf"}));
  a->block_align = add_reparam_options(cmd, o.reparam);
  add_gpu_output_options(cmd, a->gpu);
  cmd->add_flag("--eval", o.eval, "Also evaluate each result against its input (NAME.eval.json)");
  add_view_options(cmd, o.eval_options.resolution, o.eval_options.filter, "--eval-");
  add_shading_option(cmd, o.eval_options.shading, "--eval-");
  cmd->add_option("--eval-cost-grid", a->grid, "eval: relative costs, each in (0, 4], comma-separated")
      ->delimiter(',')
      ->check(cost_grid_value());
  cmd->add_option("--shard-index", a->shard_index, "This shard (default: SLURM_ARRAY_TASK_ID, JOB_COMPLETION_INDEX, AWS_BATCH_JOB_ARRAY_INDEX)");
  cmd->add_option("--shard-count", a->shard_count, "Number of shards (default: SLURM_ARRAY_TASK_COUNT, else one asset per index)")
      ->check(CLI::Range(size_t(1), size_t(1) << 40));
  cmd->add_option("--jobs", o.jobs, "Assets processed at once, each in its own process with cores/N threads")->capture_default_str()->check(CLI::Range(1u, 256u));
  cmd->add_flag("--force", o.force, "Redo assets whose results are up to date");
  cmd->add_flag("--collect", a->collect, "Process nothing: summarize every asset's report in DIR (after an array job)");
  cmd->callback([&g, a] {
    g.action = [&g, a]() -> int {
      batch::BatchOptions o = a->o;
      if (a->gpu.format == "astc") o.astc = a->gpu.astc;
      o.reparam.block = block_alignment(a->gpu, o.reparam.block, a->block_align->count() > 0);
      o.version = UVPRESS_VERSION;
      o.refs = g.refs();  // the global --allow-outside-refs, recorded in every report
      o.strict = g.strict;
      if (!a->grid.empty()) o.eval_options.cost_grid = a->grid;
      if (a->collect) {
        g.prepare_outputs({});  // --report; DIR is read, not written
        const batch::BatchSummary summary = batch::collect_batch(o);
        print_table(summary);
        g.write_report(batch::to_json(summary));
        return summary.count("ok") == summary.assets.size() ? 0 : 1;
      }
      try {
        auto env = batch::shard_from_environment([](const char* n) { return std::getenv(n); });
        size_t items = 0;
        if (!a->shard_count && !env.count && (a->shard_index || env.index)) items = batch::read_manifest(o.manifest).size();
        o.shard_index = a->shard_index.value_or(env.index.value_or(0));
        o.shard_count = a->shard_count ? *a->shard_count : env.count ? *env.count : (a->shard_index || env.index) ? items : 1;
        if (g.verbose && !env.source.empty() && !a->shard_index)
          std::fprintf(stderr, "batch: shard %zu of %zu from %s\n", o.shard_index, o.shard_count, env.source.c_str());
        if (o.shard_index >= o.shard_count)
          throw UsageError("shard index " + std::to_string(o.shard_index) + " is not below the shard count " +
                           std::to_string(o.shard_count));
      } catch (const std::invalid_argument& e) {
        throw UsageError(e.what());
      }
      g.prepare_outputs({}, {o.output_dir});
      const std::string device = g.device;
      const bool validation = g.validation, verbose = g.verbose;
      auto factory = [device, validation, verbose](unsigned threads) {
        auto request = engine::parse_device_request(device);
        if (!request) throw engine::EngineError("--device '" + device + "' is not one of auto, gpu, lavapipe, cpu");
        engine::EngineOptions eo;
        eo.validation = validation;
        eo.threads = threads;
        auto e = engine::make_engine(*request, eo);
        if (verbose) {
          auto d = e->device();
          write_line("device: " + d.backend + " " + d.name + " (" + d.type + ")");
        }
        return e;
      };
      batch::BatchSummary summary;
      try {
        summary = batch::run_batch(o, factory, write_line);
      } catch (const std::invalid_argument& e) {
        throw UsageError(e.what());
      }
      print_table(summary);
      std::fflush(stdout);
      write_line("batch: summary in " + batch::summary_path(o));
      g.write_report(batch::to_json(summary));
      return summary.count("failed") > 0 ? 1 : 0;
    };
    // Usage errors found after parsing (bad shard) exit 2 like CLI11's own.
    auto inner = g.action;
    g.action = [inner]() -> int {
      try {
        return inner();
      } catch (const UsageError& e) {
        std::fprintf(stderr, "uvpress: batch: %s (see uvpress batch --help)\n", e.what());
        return 2;
      }
    };
  });
}

}  // namespace uvpress::cli
