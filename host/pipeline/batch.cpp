#include "pipeline/batch.h"

#include "core/error.h"
#include "core/report_schema.h"
#include "core/stopwatch.h"
#include "io/asset_bytes.h"
#include "io/atomic_file.h"
#include "io/gltf_io.h"
#include "io/gltf_rules.h"
#include "io/gpu_textures.h"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <new>
#include <set>
#include <stdexcept>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace uvpress::pipeline {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

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

uint64_t fnv1a(uint64_t h, const void* data, size_t n) {
  const auto* p = static_cast<const uint8_t*>(data);
  for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
  return h;
}

// The files that make up an output asset: the main file, for .gltf its sidecars, and the
// KTX2 copies either names.
std::vector<fs::path> asset_files(const fs::path& path) {
  std::vector<fs::path> files = {path};
  try {
    const std::vector<uint8_t> bytes = io::read_file(path.string());
    if (io::extension_of(path.string()) == ".gltf")  // uvpress's .glb outputs hold the rest
      for (const auto& ref : io::external_refs(bytes)) files.push_back(path.parent_path() / ref.uri);
    for (const auto& ref : io::ktx2_sidecar_refs(bytes)) files.push_back(path.parent_path() / ref.uri);
  } catch (const InputError&) {
  }
  return files;
}

std::string to_hex(uint64_t h) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", (unsigned long long)h);
  return buf;
}

json read_json(const fs::path& path) {
  std::ifstream in(path);
  if (!in) return json();
  try {
    return json::parse(in);
  } catch (const std::exception&) {
    return json();
  }
}

fs::path output_path(const BatchItem& item, const BatchOptions& o) { return fs::path(o.output_dir) / (item.name + "." + o.format); }
fs::path report_path(const BatchItem& item, const BatchOptions& o) { return fs::path(o.output_dir) / (item.name + ".report.json"); }
fs::path eval_path(const BatchItem& item, const BatchOptions& o) { return fs::path(o.output_dir) / (item.name + ".eval.json"); }

void write_json(const fs::path& path, const json& j) {
  io::AtomicWriter w;
  w.add(path.string(), j.dump(2) + "\n");
  w.commit();
}

// A file of an asset's output that batch may delete: beside the output and named for the
// asset (what asset_files lists could name anything; the rest is not ours).
bool owned_by(const BatchItem& item, const fs::path& out, const fs::path& f) {
  return f.parent_path() == out.parent_path() && f.filename().string().rfind(item.name, 0) == 0;
}

// Removes what an earlier run left for this asset (its output files and eval report).
void remove_outputs(const BatchItem& item, const BatchOptions& o) {
  std::error_code ec;
  fs::path out = output_path(item, o);
  if (fs::exists(out, ec))
    for (const auto& f : asset_files(out))
      if (owned_by(item, out, f)) fs::remove(f, ec);
  fs::remove(eval_path(item, o), ec);
}

// The summary row of one asset report.
json summary_row(const json& report, const std::string& status) {
  json row = {{"name", report.value("name", "")}, {"input", report.value("input", "")}, {"status", status}};
  for (const char* key : {"error", "output", "seconds", "cost_ratio", "input_bytes", "output_bytes", "pixel_ratio_at_equal_q"})
    if (report.contains(key)) row[key] = report[key];
  // What was written ("reparam", "resize" when the guard found the plain resize better,
  // "untouched" when no layout could be re-parameterized) and the two q the guard compared.
  if (report.contains("reparam") && report["reparam"].is_object()) {
    const json& r = report["reparam"];
    if (r.contains("chosen")) row["written"] = r["chosen"];
    if (r.contains("guard") && r["guard"].is_object() && r["guard"].contains("q_resize"))
      row["q"] = r["guard"][r["chosen"] == "resize" ? "q_resize" : "q_reparam"], row["q_resize"] = r["guard"]["q_resize"];
  }
  return row;
}

json counts_of(const json& assets) {
  json counts = {{"ok", 0}, {"skipped", 0}, {"failed", 0}};
  for (const auto& a : assets) {
    std::string s = a["status"].get<std::string>();
    counts[s] = counts.value(s, 0) + 1;
  }
  return counts;
}

// Shared between the batch and its workers (an anonymous shared mapping).
struct SharedState {
  std::atomic<size_t> next{0};
  std::atomic<size_t> done{0};
  static constexpr size_t kMaxJobs = 256;
  std::atomic<long> current[kMaxJobs];
};
static_assert(std::atomic<size_t>::is_always_lock_free && std::atomic<long>::is_always_lock_free,
              "cross-process counters need lock-free atomics");

std::string signal_name(int sig) {
  const char* d = strsignal(sig);
  return "signal " + std::to_string(sig) + (d ? std::string(" (") + d + ")" : "");
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

std::string hash_asset(const std::string& path, const io::RefPolicy& refs) {
  std::vector<uint8_t> bytes;
  try {
    bytes = io::read_file(path);
  } catch (const InputError&) {
    return "";
  }
  uint64_t h = fnv1a(0xcbf29ce484222325ull, bytes.data(), bytes.size());
  std::vector<io::ExternalRef> refs_and_copies = io::external_refs(bytes);
  for (auto& ref : io::ktx2_sidecar_refs(bytes)) refs_and_copies.push_back(std::move(ref));
  for (const auto& ref : refs_and_copies) {
    h = fnv1a(h, ref.uri.data(), ref.uri.size() + 1);
    try {
      io::OpenRef open = io::open_ref(path, ref, refs);  // the loader's rule: no hang, no huge read
      open.file.read_chunks([&](const uint8_t* p, size_t n) { h = fnv1a(h, p, n); });
    } catch (const InputError& e) {
      // The load fails with this same line (or drops the KTX2 copy); hashing it makes a
      // fixed reference a new input, and a removed copy a stale output.
      const std::string why = e.what();
      h = fnv1a(h, why.data(), why.size() + 1);
    }
  }
  return to_hex(h);
}

json options_json(const BatchOptions& o) {
  const auto& r = o.reparam;
  json j = {{"uvpress", o.version}, {"algorithm", kReparamRevision}, {"format", o.format}, {"cost", r.size ? json(nullptr) : json(r.cost)},
            {"size", r.size}, {"max_gmsd", r.max_gmsd}, {"pot", r.power_of_two}, {"keep_aspect", r.keep_aspect}, {"score_resolution", r.score_resolution}, {"score_filter", eval::to_string(r.score_filter)}, {"score_shading", eval::to_string(r.score_shading)}, {"gutter", r.gutter == ReparamOptions::kAutoGutter ? json("auto") : json(r.gutter)}, {"block", r.block},
            {"optimize", r.optimize}, {"epsilon", r.triangle.epsilon}, {"evaluations", r.triangle.evaluations},
            {"view_size", r.triangle.view_size}, {"seed", r.triangle.seed}, {"early_stop", r.triangle.early_stop}, {"eval", o.eval},
            {"allow_outside_refs", o.refs.allow_outside},
            {"texture_format", o.astc ? json{{"astc", io::block_name(*o.astc)}, {"quality", io::to_string(o.astc->quality)}} : json("source")}};
  if (o.strict) j["strict"] = true;  // absent when off: earlier results stay current
  if (o.eval) j["eval_options"] = {{"cost_grid", o.eval_options.cost_grid}, {"resolution", o.eval_options.resolution}, {"filter", eval::to_string(o.eval_options.filter)}, {"shading", eval::to_string(o.eval_options.shading)}};
  return j;
}

std::string summary_path(const BatchOptions& o) {
  fs::path dir(o.output_dir);
  if (o.shard_count <= 1) return (dir / "summary.json").string();
  return (dir / ("summary-shard-" + std::to_string(o.shard_index) + "-of-" + std::to_string(o.shard_count) + ".json")).string();
}

bool up_to_date(const BatchItem& item, const BatchOptions& o) {
  json r = read_json(report_path(item, o));
  if (!r.is_object() || r.value("status", "") != "ok") return false;
  if (r.value("input_hash", "") != hash_asset(item.input, o.refs)) return false;
  if (!r.contains("options") || r["options"] != options_json(o)) return false;
  if (r.value("output_hash", "") != hash_asset(output_path(item, o).string())) return false;
  if (o.eval && !read_json(eval_path(item, o)).is_object()) return false;
  return true;
}

json process_asset(const BatchItem& item, const BatchOptions& o, engine::Engine* engine, const std::string& engine_error) {
  const Stopwatch t0;
  const fs::path out = output_path(item, o);
  json report = {{"schema", kReportSchema}, {"name", item.name}, {"input", item.input}, {"position", item.position},
                 {"input_hash", hash_asset(item.input, o.refs)}, {"options", options_json(o)}};
  try {
    if (!engine) throw engine::EngineError(engine_error.empty() ? "no engine" : engine_error);
    io::GltfFile file = io::load_gltf(item.input, o.refs);
    // The input's own glTF errors: refused under --strict, else a warning (the output keeps
    // what reparam does not rewrite).
    const std::vector<io::RuleIssue> issues = io::check_rules(file);
    report["input_validation"] = io::validation_json(issues);
    if (!issues.empty() && o.strict) throw InputError(item.input, io::describe_issues(issues) + ": refused (--strict)");
    report["input_bytes"] = io::asset_bytes(item.input, o.refs).total();  // JSON, buffers and images
    auto r = reparam(file, *engine, o.reparam).to_json();
    if (!issues.empty()) r["warnings"].push_back("the input has " + io::describe_issues(issues));
    if (o.astc) r["gpu_textures"] = io::gpu_textures_report(io::attach_astc_textures(file, *o.astc), *o.astc);
    // Files of an earlier run's output that this one no longer names (a KTX2 copy, when
    // --texture-format changed) are removed once the new output is in place.
    const std::vector<fs::path> earlier = fs::exists(out) ? asset_files(out) : std::vector<fs::path>();
    io::save_gltf(file, out.string());
    {
      const std::vector<fs::path> now = asset_files(out);
      std::error_code ec;
      for (const fs::path& f : earlier)
        if (std::find(now.begin(), now.end(), f) == now.end() && owned_by(item, out, f)) fs::remove(f, ec);
    }
    report["output"] = out.string();
    report["output_bytes"] = io::asset_bytes(out.string()).total();
    report["output_hash"] = hash_asset(out.string());
    report["device"] = r["device"];
    report["backend"] = r["backend"];
    report["cost_ratio"] = r["cost_ratio"];
    report["warnings"] = r["warnings"];
    report["reparam"] = r;
    if (o.eval) {
      io::GltfFile reference = io::load_gltf(item.input, o.refs);
      io::GltfFile result = io::load_gltf(out.string());
      eval::EvalOptions eo = o.eval_options;
      eo.artifacts = false;
      json e = eval::evaluate(reference, {{"reparam", &result}}, *engine, eo).to_json();
      write_json(eval_path(item, o), e);
      report["eval"] = eval_path(item, o).string();
      for (const auto& s : e["savings"])
        if (s.value("layout", "") == "reparam" && s.value("vs", "") == "input") report["pixel_ratio_at_equal_q"] = s["pixel_ratio_at_equal_q"];
    }
    report["status"] = "ok";
  } catch (const InputError& e) {
    report["status"] = "failed";
    report["error"] = e.file() + ": " + e.what();
  } catch (const engine::EngineError& e) {
    report["status"] = "failed";
    report["error"] = std::string("device: ") + e.what();
  } catch (const std::bad_alloc&) {
    report["status"] = "failed";
    report["error"] = "out of memory";
  } catch (const std::exception& e) {
    report["status"] = "failed";
    report["error"] = std::string("internal error: ") + e.what();
  }
  report["seconds"] = t0.seconds();
  if (report["status"] == "failed") {
    for (const char* key : {"output", "output_bytes", "output_hash", "eval"}) report.erase(key);
    remove_outputs(item, o);
  }
  try {
    write_json(report_path(item, o), report);
  } catch (const std::exception& e) {
    report["status"] = "failed";
    report["error"] = std::string("cannot write the report: ") + e.what();
  }
  return report;
}

json run_batch(const BatchOptions& o, const EngineFactory& make_engine, const BatchLog& log) {
  const Stopwatch t0;
  if (o.format != "glb" && o.format != "gltf") throw std::invalid_argument("--format must be glb or gltf");
  if (o.jobs == 0 || o.jobs > SharedState::kMaxJobs)
    throw std::invalid_argument("--jobs must be between 1 and " + std::to_string(SharedState::kMaxJobs));
  std::vector<BatchItem> items = select_shard(read_manifest(o.manifest), o.shard_index, o.shard_count);
  std::error_code ec;
  fs::create_directories(o.output_dir, ec);
  if (!fs::is_directory(o.output_dir)) throw InputError(o.output_dir, "cannot create the output folder" + (ec ? ": " + ec.message() : ""));

  // Skip what is done; the rest goes to the workers.
  std::vector<BatchItem> todo;
  std::map<size_t, json> rows;  // by manifest position
  for (const auto& it : items) {
    if (!o.force && up_to_date(it, o)) {
      json r = read_json(report_path(it, o));
      rows[it.position] = summary_row(r, "skipped");
      if (log) log("batch: " + it.name + ": skipped (up to date)");
    } else {
      todo.push_back(it);
    }
  }
  const size_t total = todo.size();
  auto line_for = [&](size_t done, const json& r) {
    std::string s = "batch [" + std::to_string(done) + "/" + std::to_string(total) + "] " + r.value("name", "") + ": ";
    char buf[96];
    if (r.value("status", "") == "ok") {
      std::snprintf(buf, sizeof buf, "ok, cost ratio %.3f, %.1f s", r.value("cost_ratio", 0.0), r.value("seconds", 0.0));
      s += buf;
    } else {
      s += "FAILED: " + r.value("error", std::string("unknown error"));
    }
    return s;
  };
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  const unsigned jobs = unsigned(std::min<size_t>(o.jobs, std::max<size_t>(total, 1)));
  const unsigned threads = o.jobs > 1 ? std::max(1u, hw / jobs) : 0;

  if (!o.isolate) {
    std::unique_ptr<engine::Engine> engine;
    std::string engine_error;
    try {
      if (total) engine = make_engine(threads);
    } catch (const std::exception& e) {
      engine_error = e.what();
    }
    for (size_t k = 0; k < total; ++k) {
      json r = process_asset(todo[k], o, engine.get(), engine_error);
      if (log) log(line_for(k + 1, r));
    }
  } else if (total) {
    void* mem = mmap(nullptr, sizeof(SharedState), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    if (mem == MAP_FAILED) throw std::runtime_error(std::string("mmap: ") + std::strerror(errno));
    auto* shared = new (mem) SharedState();
    for (auto& c : shared->current) c.store(-1);
    const pid_t batch_pid = getpid();
    std::fflush(nullptr);
    auto spawn = [&](unsigned w) -> pid_t {
      pid_t pid = fork();
      if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
      if (pid > 0) return pid;
      // Worker: dies with the batch, never returns into the caller's stack.
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (getppid() != batch_pid) _exit(1);
      int status = 0;
      try {
        if (threads) omp_set_num_threads(int(threads));
        std::unique_ptr<engine::Engine> engine;
        std::string engine_error;
        try {
          engine = make_engine(threads);
        } catch (const std::exception& e) {
          engine_error = e.what();
        }
        for (;;) {
          size_t k = shared->next.fetch_add(1);
          if (k >= total) break;
          shared->current[w].store(long(k));
          json r = process_asset(todo[k], o, engine.get(), engine_error);
          size_t done = shared->done.fetch_add(1) + 1;
          shared->current[w].store(-1);
          if (log) log(line_for(done, r));
        }
      } catch (...) {
        status = 1;
      }
      std::fflush(nullptr);
      _exit(status);
    };
    std::map<pid_t, unsigned> workers;
    for (unsigned w = 0; w < jobs; ++w) workers[spawn(w)] = w;
    while (!workers.empty()) {
      int status = 0;
      pid_t pid = waitpid(-1, &status, 0);
      if (pid < 0) {
        if (errno == EINTR) continue;
        break;
      }
      auto it = workers.find(pid);
      if (it == workers.end()) continue;
      unsigned w = it->second;
      workers.erase(it);
      long k = shared->current[w].exchange(-1);
      if (k >= 0) {
        // The worker died inside an asset: fail that asset, keep going with the rest.
        const BatchItem& item = todo[size_t(k)];
        std::string why = WIFSIGNALED(status) ? "crashed with " + signal_name(WTERMSIG(status))
                                              : "worker exited with status " + std::to_string(WEXITSTATUS(status));
        json r = {{"schema", kReportSchema}, {"name", item.name}, {"input", item.input}, {"position", item.position},
                  {"input_hash", hash_asset(item.input, o.refs)}, {"options", options_json(o)}, {"status", "failed"},
                  {"error", item.input + ": " + why}};
        remove_outputs(item, o);
        try {
          write_json(report_path(item, o), r);
        } catch (const std::exception&) {
        }
        size_t done = shared->done.fetch_add(1) + 1;
        if (log) log(line_for(done, r));
      }
      if (shared->next.load() < total) workers[spawn(w)] = w;
    }
    shared->~SharedState();
    munmap(mem, sizeof(SharedState));
  }

  // The summary from the reports on disk (the workers' results).
  for (const auto& it : todo) {
    json r = read_json(report_path(it, o));
    if (!r.is_object() || r.value("input_hash", "") != hash_asset(it.input, o.refs) || !r.contains("status"))
      r = {{"name", it.name}, {"input", it.input}, {"status", "failed"}, {"error", it.input + ": no report was written"}};
    rows[it.position] = summary_row(r, r["status"].get<std::string>());
  }
  json assets = json::array();
  for (auto& [pos, row] : rows) assets.push_back(row);
  json summary = {{"schema", kReportSchema}, {"manifest", o.manifest}, {"output_dir", o.output_dir},
                  {"shard", {{"index", o.shard_index}, {"count", o.shard_count}}},
                  {"jobs", o.jobs}, {"threads_per_job", threads}, {"options", options_json(o)},
                  {"counts", counts_of(assets)}, {"assets", assets}, {"seconds", t0.seconds()}};
  write_json(summary_path(o), summary);
  return summary;
}

json collect_batch(const BatchOptions& o) {
  const Stopwatch t0;
  std::vector<BatchItem> items = read_manifest(o.manifest);
  json assets = json::array();
  for (const auto& it : items) {
    json r = read_json(report_path(it, o));
    if (!r.is_object() || !r.contains("status")) {
      assets.push_back({{"name", it.name}, {"input", it.input}, {"status", "missing"}, {"error", "no report in " + o.output_dir}});
      continue;
    }
    std::string status = r["status"].get<std::string>();
    if (status == "ok" && (r.value("input_hash", "") != hash_asset(it.input, o.refs) ||
                           r.value("output_hash", "") != hash_asset(output_path(it, o).string()))) {
      status = "stale";
      r["error"] = "the input or output changed since the report was written";
    }
    assets.push_back(summary_row(r, status));
  }
  BatchOptions whole = o;
  whole.shard_index = 0, whole.shard_count = 1;
  json summary = {{"schema", kReportSchema}, {"manifest", o.manifest}, {"output_dir", o.output_dir}, {"collected", true},
                  {"options", options_json(o)}, {"counts", counts_of(assets)}, {"assets", assets},
                  {"seconds", t0.seconds()}};
  write_json(summary_path(whole), summary);
  return summary;
}

}  // namespace uvpress::pipeline
