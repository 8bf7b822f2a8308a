#include "batch/manifest.h"

#include "core/error.h"

#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>

namespace uvpress::batch {

namespace fs = std::filesystem;

namespace {

std::string trim(const std::string& s) {
  size_t a = s.find_first_not_of(" \t\r\n"), b = s.find_last_not_of(" \t\r\n");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

std::string safe_name(std::string s) {
  for (auto& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';
  if (s.empty() || s[0] == '.') s = "asset" + s;
  return s;
}

}  // namespace

std::vector<BatchItem> read_manifest(const std::string& manifest) {
  std::ifstream in(manifest);
  std::error_code ec;
  if (!fs::exists(manifest, ec)) throw InputError(manifest, "file not found");
  if (!in) throw InputError(manifest, "cannot open for reading");
  const fs::path base = fs::path(manifest).parent_path();
  std::vector<BatchItem> items;
  std::string line;
  while (std::getline(in, line)) {
    line = trim(line);
    if (line.empty() || line[0] == '#') continue;
    if (line.find('\0') != std::string::npos) throw InputError(manifest, "not a text file (NUL byte in a line)");
    fs::path p(line);
    BatchItem item;
    item.position = items.size();
    item.input = p.is_absolute() || base.empty() ? p.string() : (base / p).string();
    item.name = safe_name(p.stem().string());
    items.push_back(std::move(item));
  }
  if (items.empty()) throw InputError(manifest, "lists no asset (one path a line; '#' starts a comment)");
  std::map<std::string, size_t> uses;
  for (const auto& it : items) ++uses[it.name];
  for (auto& it : items)
    if (uses[it.name] > 1) it.name += "-" + std::to_string(it.position + 1);
  return items;
}

ShardSpec shard_from_environment(const std::function<const char*(const char*)>& get_env) {
  auto number = [&](const char* name) -> std::optional<size_t> {
    const char* v = get_env(name);
    if (!v || !*v) return std::nullopt;
    char* end = nullptr;
    errno = 0;
    long long n = std::strtoll(v, &end, 10);
    if (*end != '\0' || n < 0 || errno) throw std::invalid_argument(std::string(name) + "='" + v + "' is not a non-negative integer");
    return size_t(n);
  };
  ShardSpec s;
  if (auto id = number("SLURM_ARRAY_TASK_ID")) {
    size_t min = number("SLURM_ARRAY_TASK_MIN").value_or(0);
    if (*id < min) throw std::invalid_argument("SLURM_ARRAY_TASK_ID is below SLURM_ARRAY_TASK_MIN");
    s.index = *id - min;
    s.count = number("SLURM_ARRAY_TASK_COUNT");
    s.source = "SLURM_ARRAY_TASK_ID";
  } else if (auto k = number("JOB_COMPLETION_INDEX")) {
    s.index = k, s.source = "JOB_COMPLETION_INDEX";
  } else if (auto a = number("AWS_BATCH_JOB_ARRAY_INDEX")) {
    s.index = a, s.source = "AWS_BATCH_JOB_ARRAY_INDEX";
  }
  return s;
}

std::vector<BatchItem> select_shard(const std::vector<BatchItem>& items, size_t index, size_t count) {
  if (count == 0) throw std::invalid_argument("shard count must be at least 1");
  if (index >= count)
    throw std::invalid_argument("shard index " + std::to_string(index) + " is not below the shard count " + std::to_string(count));
  std::vector<BatchItem> out;
  for (const auto& it : items)
    if (it.position % count == index) out.push_back(it);
  return out;
}

}  // namespace uvpress::batch
