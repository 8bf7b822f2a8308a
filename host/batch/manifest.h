// batch's work list: the assets a manifest names, and the share of them one array task
// (shard) runs.
//
// - Manifest: one asset path a line; blank lines and lines starting with '#' are ignored;
//   relative paths are relative to the manifest's folder. Each asset gets a name, its
//   file stem (letters, digits, '-', '_', '.'); stems that occur more than once get
//   "-<line number among the assets>" so that every shard computes the same names.
// - Shards: the assets whose 0-based manifest position p has p % count == index.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace uvpress::batch {

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

}  // namespace uvpress::batch
