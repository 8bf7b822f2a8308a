// `uvpress batch`: reparam (and eval) over a manifest of assets, for studios and GPU farms.
//
// - Manifest: one asset path a line; blank lines and lines starting with '#' are ignored;
//   relative paths are relative to the manifest's folder. Each asset gets a name, its
//   file stem (letters, digits, '-', '_', '.'); stems that occur more than once get
//   "-<line number among the assets>" so that every shard computes the same names.
// - Outputs in DIR, per asset: NAME.glb (or NAME.gltf + sidecars; with --texture-format
//   astc also NAME_<image>.ktx2 beside it), NAME.eval.json with
//   --eval, and NAME.report.json, written last: the report is the commit marker. Every file
//   is written atomically (temporary + rename). A failed asset gets a report with
//   "status": "failed" and "error", and no output (a stale one from an earlier run is
//   removed). Per shard: summary.json (or summary-shard-I-of-N.json).
// - Resume: an asset is skipped when its report says "ok", records the same input hash
//   (FNV-1a 64 over the asset and every file it references) and the same options, and its
//   outputs still hash to what the report recorded. Failed assets are retried.
// - Shards: the assets whose 0-based manifest position p has p % count == index.
// - Isolation: assets run in worker processes (forked before any engine or OpenMP thread
//   exists, so fork is safe), `jobs` of them at once, taking the next asset from a shared
//   counter. A worker that dies (a crash, an out-of-memory kill) fails only the asset it
//   was on; a fresh worker carries on with the rest. Workers die with the batch (SIGKILL
//   on parent death). With jobs > 1, each worker's CPU threads (CPU backend and OpenMP)
//   are the machine's cores divided by jobs; on a GPU each worker has its own device
//   context and the driver time-slices them.
#pragma once

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
#include <vector>

namespace uvpress::pipeline {

struct BatchItem {
  size_t position = 0;  // 0-based among the manifest's assets
  std::string input;    // path as usable from the current directory
  std::string name;     // output base name, unique within the manifest
};

// Throws InputError(manifest, reason) when it cannot be read or lists no asset.
std::vector<BatchItem> read_manifest(const std::string& manifest);

struct ShardSpec {
  std::optional<size_t> index, count;
  std::string source;  // which variable set them ("" when none)
};
// SLURM_ARRAY_TASK_ID (minus SLURM_ARRAY_TASK_MIN) with SLURM_ARRAY_TASK_COUNT, else
// JOB_COMPLETION_INDEX (Kubernetes Indexed Jobs), else AWS_BATCH_JOB_ARRAY_INDEX. Without a
// count the batch runs one asset per index. Throws std::invalid_argument for a set
// variable that is not a non-negative integer.
ShardSpec shard_from_environment(const std::function<const char*(const char*)>& get_env);

// The assets of shard `index` of `count`. Throws std::invalid_argument when index >= count.
std::vector<BatchItem> select_shard(const std::vector<BatchItem>& items, size_t index, size_t count);

// FNV-1a 64 (hex) over a file and every file its buffers and images name (.gltf or .glb),
// read only as `refs` allows (io/references.h: no FIFO, device or oversized file is read; a
// refused reference adds its error line instead). "" when the file cannot be read.
std::string hash_asset(const std::string& path, const io::RefPolicy& refs = {});

struct BatchOptions {
  std::string manifest;
  std::string output_dir;
  ReparamOptions reparam;
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

// Runs the shard. Returns the summary (also written to DIR/summary*.json): shard, jobs,
// options, counts {ok, skipped, failed}, assets [{name, input, status, error, output,
// seconds, cost_ratio, input_bytes, output_bytes, report}], seconds. Throws InputError for
// an unreadable manifest or an output folder that cannot be created,
// std::invalid_argument for a bad shard.
nlohmann::ordered_json run_batch(const BatchOptions& options, const EngineFactory& make_engine,
                                 const BatchLog& log = {});

// Builds the summary of every asset in the manifest from the reports in DIR (after an
// array job): status "ok", "failed" or "missing". Written to DIR/summary.json.
nlohmann::ordered_json collect_batch(const BatchOptions& options);

// Where the summary of a shard goes.
std::string summary_path(const BatchOptions& options);

}  // namespace uvpress::pipeline
