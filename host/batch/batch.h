// `uvpress batch`: reparam (and eval) over a manifest of assets, for studios and GPU farms.
//
// - The assets and shards: batch/manifest.h.
// - Outputs in DIR, per asset: NAME.glb (or NAME.gltf + sidecars; with --texture-format
//   astc also NAME_<image>.ktx2 beside it), NAME.eval.json with
//   --eval, and NAME.report.json, written last: the report is the commit marker. Every file
//   is written atomically (temporary + rename). A failed asset gets a report with
//   "status": "failed" and "error", and no output (a stale one from an earlier run is
//   removed). Per shard: summary.json (or summary-shard-I-of-N.json; batch/summary.h).
// - Resume: an asset is skipped when its report says "ok", records the same input hash
//   (batch/input_hash.h) and the same options, and its outputs still hash to what the
//   report recorded. Failed assets are retried.
// - Isolation: assets run in worker processes (batch/workers.h), `jobs` of them at once.
//   With jobs > 1, each worker's CPU threads (CPU backend and OpenMP) are the machine's
//   cores divided by jobs; on a GPU each worker has its own device context and the driver
//   time-slices them.
#pragma once

#include "batch/manifest.h"
#include "batch/summary.h"
#include "engine.h"
#include "eval/eval.h"
#include "io/astc_codec.h"
#include "io/references.h"
#include "pipeline/reparam.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace uvpress::batch {

struct BatchOptions {
  std::string manifest;
  std::string output_dir;
  pipeline::ReparamOptions reparam;
  bool eval = false;
  eval::EvalOptions eval_options;
  std::string format = "glb";  // glb | gltf
  // --texture-format astc: every image also as an ASTC KTX2 copy beside NAME.glb/.gltf
  // (io/gpu_textures.h), reported as `gpu_textures`; part of the output's hash.
  std::optional<io::AstcOptions> astc;
  size_t shard_index = 0, shard_count = 1;
  unsigned jobs = 1;
  bool force = false;    // ignore earlier results
  bool isolate = true;   // false: run in this process, one asset after another (tests)
  std::string version;   // recorded in the reports (and part of the options compared)
  io::RefPolicy refs;    // --allow-outside-refs, for loading and hashing inputs (recorded)
  // --strict: an input that breaks the glTF rules checked on load (io/gltf_rules.h) fails
  // instead of carrying a warning (recorded when set).
  bool strict = false;
};

// The options as recorded in each report and compared on resume.
nlohmann::ordered_json options_json(const BatchOptions& options);

// Makes an engine for a worker with `threads` CPU threads (0: all cores).
using EngineFactory = std::function<std::unique_ptr<engine::Engine>(unsigned threads)>;
// One line of progress (no newline).
using BatchLog = std::function<void(const std::string& line)>;

// True when `item`'s earlier result in options.output_dir is complete and current.
bool up_to_date(const BatchItem& item, const BatchOptions& options);

// Runs one asset: reparam, save, eval, report. Never throws: a failure is recorded in the
// returned (and written) report as "status": "failed" with "error".
nlohmann::ordered_json process_asset(const BatchItem& item, const BatchOptions& options, engine::Engine* engine,
                                     const std::string& engine_error = {});

// Runs the shard. Returns its summary (also written to summary_path). Throws InputError for
// an unreadable manifest or an output folder that cannot be created,
// std::invalid_argument for a bad shard, format or job count.
BatchSummary run_batch(const BatchOptions& options, const EngineFactory& make_engine, const BatchLog& log = {});

// Builds the summary of every asset in the manifest from the reports in DIR (after an
// array job): status "ok", "failed", "missing" or "stale". Written to DIR/summary.json.
BatchSummary collect_batch(const BatchOptions& options);

// Where the summary of a shard goes.
std::string summary_path(const BatchOptions& options);

}  // namespace uvpress::batch
