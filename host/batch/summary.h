// batch's summary: one row per asset (from its report on disk) and the counts, as
// summary.json (or summary-shard-I-of-N.json) and `--report` carry them, and as the table
// on stdout shows them.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace uvpress::batch {

// One asset. Optional fields are absent from the JSON when unset; a number that is NaN is
// written as null (the report held null: eval found no common q range, a layout that
// could not be scored).
struct AssetRow {
  std::string name, input;
  std::string status;  // ok | skipped | failed (run_batch); ok | failed | missing | stale (collect_batch)
  std::optional<std::string> error;   // FILE: reason
  std::optional<std::string> output;  // the written asset
  std::optional<double> seconds;      // the asset's run
  std::optional<double> cost_ratio;   // new / old texels
  std::optional<uint64_t> input_bytes, output_bytes;  // the whole asset: JSON, buffers, images
  std::optional<double> pixel_ratio_at_equal_q;       // with --eval: against the input
  // What was written: "reparam", "resize" when the guard found the plain resize better,
  // "untouched" when no layout could be re-parameterized.
  std::optional<std::string> written;
  // The written file's q and the plain resize's, as the guard compared them (both or none).
  std::optional<double> q, q_resize;
  std::optional<double> q_far, q_far_resize;  // the same from afar (the guard's far views)
};

// The row of an asset's report (NAME.report.json) under `status`.
AssetRow row_from_report(const nlohmann::ordered_json& report, const std::string& status);

struct BatchSummary {
  std::string manifest, output_dir;
  bool collected = false;  // collect_batch: the whole manifest, no shard, jobs or threads
  size_t shard_index = 0, shard_count = 1;
  unsigned jobs = 1, threads_per_job = 0;  // 0 threads: all cores
  nlohmann::ordered_json options;          // options_json, as every report records them
  std::vector<AssetRow> assets;            // in manifest order
  double seconds = 0;

  // Rows with this status.
  size_t count(const std::string& status) const;
};

// The summary file's JSON: schema, manifest, output_dir, then shard {index, count}, jobs,
// threads_per_job (or collected: true), options, counts {ok, skipped, failed, then any other
// status in order of first appearance}, assets [rows], seconds.
nlohmann::ordered_json to_json(const AssetRow& row);
nlohmann::ordered_json to_json(const BatchSummary& summary);

}  // namespace uvpress::batch
