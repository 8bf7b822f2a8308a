#include "batch/batch.h"

#include "batch/input_hash.h"
#include "batch/workers.h"
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
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <thread>

namespace uvpress::batch {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

namespace {

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

}  // namespace

json options_json(const BatchOptions& o) {
  const auto& r = o.reparam;
  json j = {{"uvpress", o.version}, {"algorithm", pipeline::kReparamRevision}, {"format", o.format}, {"cost", r.size ? json(nullptr) : json(r.cost)},
            {"size", r.size}, {"max_gmsd", r.max_gmsd}, {"pot", r.power_of_two}, {"keep_aspect", r.keep_aspect}, {"score_resolution", r.score_resolution}, {"score_filter", eval::to_string(r.score_filter)}, {"score_shading", eval::to_string(r.score_shading)}, {"gutter", r.gutter == pipeline::ReparamOptions::kAutoGutter ? json("auto") : json(r.gutter)}, {"block", r.block},
            {"optimize", r.optimize}, {"epsilon", r.triangle.epsilon}, {"evaluations", r.triangle.evaluations},
            {"view_size", r.triangle.view_size}, {"seed", r.triangle.seed}, {"early_stop", r.triangle.early_stop}, {"eval", o.eval},
            {"allow_outside_refs", o.refs.allow_outside},
            {"texture_format", o.astc ? json{{"astc", io::block_name(*o.astc)}, {"quality", io::to_string(o.astc->quality)}} : json("source")}};
  if (o.strict) j["strict"] = true;  // absent when off: earlier results stay current
  // Likewise each of these only when it differs from reparam's default (an explicit
  // --epsilon equal to the default turns rate control off: a different result).
  const pipeline::ReparamOptions defaults;
  if (r.rate_control != defaults.rate_control) j["rate_control"] = r.rate_control;
  if (r.triangle.min_texels_per_pixel != defaults.triangle.min_texels_per_pixel)
    j["view_texels_per_pixel"] = r.triangle.min_texels_per_pixel;
  if (r.exact_texels != defaults.exact_texels) j["exact_texels"] = r.exact_texels;
  if (r.candidates != defaults.candidates) j["candidates"] = r.candidates;
  if (r.guard != defaults.guard) j["guard"] = r.guard;
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
    pipeline::ReparamResult r = pipeline::reparam(file, *engine, o.reparam);
    if (!issues.empty()) r.warnings.push_back("the input has " + io::describe_issues(issues));
    json reparam_report = r.to_json();
    if (o.astc) reparam_report["gpu_textures"] = io::gpu_textures_report(io::attach_astc_textures(file, *o.astc), *o.astc);
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
    report["device"] = r.device.name;
    report["backend"] = r.device.backend;
    report["cost_ratio"] = r.cost_ratio;
    report["warnings"] = r.warnings;
    report["reparam"] = std::move(reparam_report);
    if (o.eval) {
      io::GltfFile reference = io::load_gltf(item.input, o.refs);
      io::GltfFile result = io::load_gltf(out.string());
      eval::EvalOptions eo = o.eval_options;
      eo.artifacts = false;
      const eval::EvalResult e = eval::evaluate(reference, {{"reparam", &result}}, *engine, eo);
      write_json(eval_path(item, o), e.to_json());
      report["eval"] = eval_path(item, o).string();
      for (const auto& s : e.savings)
        if (s.layout == "reparam" && s.vs == "input")
          report["pixel_ratio_at_equal_q"] = s.savings.points ? json(s.savings.ratio) : json(nullptr);
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


BatchSummary run_batch(const BatchOptions& o, const EngineFactory& make_engine, const BatchLog& log) {
  const Stopwatch t0;
  if (o.format != "glb" && o.format != "gltf") throw std::invalid_argument("--format must be glb or gltf");
  if (o.jobs == 0 || o.jobs > kMaxWorkers)
    throw std::invalid_argument("--jobs must be between 1 and " + std::to_string(kMaxWorkers));
  std::vector<BatchItem> items = select_shard(read_manifest(o.manifest), o.shard_index, o.shard_count);
  std::error_code ec;
  fs::create_directories(o.output_dir, ec);
  if (!fs::is_directory(o.output_dir)) throw InputError(o.output_dir, "cannot create the output folder" + (ec ? ": " + ec.message() : ""));

  // Skip what is done; the rest goes to the workers.
  std::vector<BatchItem> todo;
  std::map<size_t, AssetRow> rows;  // by manifest position
  for (const auto& it : items) {
    if (!o.force && up_to_date(it, o)) {
      rows[it.position] = row_from_report(read_json(report_path(it, o)), "skipped");
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
    auto setup = [&]() -> WorkerTask {
      if (threads) omp_set_num_threads(int(threads));
      std::shared_ptr<engine::Engine> engine;
      std::string engine_error;
      try {
        engine = make_engine(threads);
      } catch (const std::exception& e) {
        engine_error = e.what();
      }
      return [&, engine, engine_error](size_t k, const std::function<size_t()>& finished) {
        json r = process_asset(todo[k], o, engine.get(), engine_error);
        const size_t done = finished();
        if (log) log(line_for(done, r));
      };
    };
    // A worker that died inside an asset: fail that asset, keep going with the rest.
    auto died = [&](size_t k, const std::string& why, const std::function<size_t()>& finished) {
      const BatchItem& item = todo[k];
      json r = {{"schema", kReportSchema}, {"name", item.name}, {"input", item.input}, {"position", item.position},
                {"input_hash", hash_asset(item.input, o.refs)}, {"options", options_json(o)}, {"status", "failed"},
                {"error", item.input + ": " + why}};
      remove_outputs(item, o);
      try {
        write_json(report_path(item, o), r);
      } catch (const std::exception&) {
      }
      const size_t done = finished();
      if (log) log(line_for(done, r));
    };
    run_in_workers(total, jobs, setup, died);
  }

  // The summary from the reports on disk (the workers' results).
  for (const auto& it : todo) {
    json r = read_json(report_path(it, o));
    if (!r.is_object() || r.value("input_hash", "") != hash_asset(it.input, o.refs) || !r.contains("status"))
      r = {{"name", it.name}, {"input", it.input}, {"status", "failed"}, {"error", it.input + ": no report was written"}};
    rows[it.position] = row_from_report(r, r["status"].get<std::string>());
  }
  BatchSummary summary;
  summary.manifest = o.manifest, summary.output_dir = o.output_dir;
  summary.shard_index = o.shard_index, summary.shard_count = o.shard_count;
  summary.jobs = o.jobs, summary.threads_per_job = threads;
  summary.options = options_json(o);
  for (auto& [pos, row] : rows) summary.assets.push_back(std::move(row));
  summary.seconds = t0.seconds();
  write_json(summary_path(o), to_json(summary));
  return summary;
}

BatchSummary collect_batch(const BatchOptions& o) {
  const Stopwatch t0;
  BatchSummary summary;
  summary.manifest = o.manifest, summary.output_dir = o.output_dir, summary.collected = true;
  summary.options = options_json(o);
  for (const auto& it : read_manifest(o.manifest)) {
    json r = read_json(report_path(it, o));
    if (!r.is_object() || !r.contains("status")) {
      AssetRow missing;
      missing.name = it.name, missing.input = it.input, missing.status = "missing", missing.error = "no report in " + o.output_dir;
      summary.assets.push_back(std::move(missing));
      continue;
    }
    std::string status = r["status"].get<std::string>();
    if (status == "ok" && (r.value("input_hash", "") != hash_asset(it.input, o.refs) ||
                           r.value("output_hash", "") != hash_asset(output_path(it, o).string()))) {
      status = "stale";
      r["error"] = "the input or output changed since the report was written";
    }
    summary.assets.push_back(row_from_report(r, status));
  }
  summary.seconds = t0.seconds();
  BatchOptions whole = o;
  whole.shard_index = 0, whole.shard_count = 1;
  write_json(summary_path(whole), to_json(summary));
  return summary;
}

}  // namespace uvpress::batch
