#include "batch/summary.h"

#include "core/report_schema.h"

#include <algorithm>
#include <limits>

namespace uvpress::batch {

using json = nlohmann::ordered_json;

namespace {

// A report's number as a row keeps it: absent stays absent, null becomes NaN (written as
// null again).
std::optional<double> number(const json& object, const char* key) {
  if (!object.contains(key)) return std::nullopt;
  const json& v = object[key];
  return v.is_null() ? std::numeric_limits<double>::quiet_NaN() : v.get<double>();
}

std::optional<uint64_t> count_of_bytes(const json& object, const char* key) {
  if (!object.contains(key)) return std::nullopt;
  return object[key].get<uint64_t>();
}

std::optional<std::string> text(const json& object, const char* key) {
  if (!object.contains(key)) return std::nullopt;
  return object[key].get<std::string>();
}

}  // namespace

AssetRow row_from_report(const json& report, const std::string& status) {
  AssetRow row;
  row.name = report.value("name", "");
  row.input = report.value("input", "");
  row.status = status;
  row.error = text(report, "error");
  row.output = text(report, "output");
  row.seconds = number(report, "seconds");
  row.cost_ratio = number(report, "cost_ratio");
  row.input_bytes = count_of_bytes(report, "input_bytes");
  row.output_bytes = count_of_bytes(report, "output_bytes");
  row.pixel_ratio_at_equal_q = number(report, "pixel_ratio_at_equal_q");
  if (report.contains("reparam") && report["reparam"].is_object()) {
    const json& r = report["reparam"];
    row.written = text(r, "chosen");
    if (r.contains("guard") && r["guard"].is_object() && r["guard"].contains("q_resize")) {
      row.q = number(r["guard"], r.value("chosen", "") == "resize" ? "q_resize" : "q_reparam");
      row.q_resize = number(r["guard"], "q_resize");
      if (r["guard"].contains("far") && r["guard"]["far"].is_object()) {
        const json& far = r["guard"]["far"];
        row.q_far = number(far, r.value("chosen", "") == "resize" ? "q_resize" : "q_reparam");
        row.q_far_resize = number(far, "q_resize");
      }
    }
  }
  return row;
}

size_t BatchSummary::count(const std::string& status) const {
  return size_t(std::count_if(assets.begin(), assets.end(), [&](const AssetRow& a) { return a.status == status; }));
}

json to_json(const AssetRow& row) {
  json j = {{"name", row.name}, {"input", row.input}, {"status", row.status}};
  if (row.error) j["error"] = *row.error;
  if (row.output) j["output"] = *row.output;
  if (row.seconds) j["seconds"] = *row.seconds;
  if (row.cost_ratio) j["cost_ratio"] = *row.cost_ratio;
  if (row.input_bytes) j["input_bytes"] = *row.input_bytes;
  if (row.output_bytes) j["output_bytes"] = *row.output_bytes;
  if (row.pixel_ratio_at_equal_q) j["pixel_ratio_at_equal_q"] = *row.pixel_ratio_at_equal_q;
  if (row.written) j["written"] = *row.written;
  if (row.q) j["q"] = *row.q;
  if (row.q_resize) j["q_resize"] = *row.q_resize;
  if (row.q_far) j["q_far"] = *row.q_far;
  if (row.q_far_resize) j["q_far_resize"] = *row.q_far_resize;
  return j;
}

json to_json(const BatchSummary& s) {
  json counts = {{"ok", 0}, {"skipped", 0}, {"failed", 0}};
  json assets = json::array();
  for (const auto& a : s.assets) {
    counts[a.status] = counts.value(a.status, 0) + 1;
    assets.push_back(to_json(a));
  }
  json j = {{"schema", kReportSchema}, {"manifest", s.manifest}, {"output_dir", s.output_dir}};
  if (s.collected) {
    j["collected"] = true;
  } else {
    j["shard"] = {{"index", s.shard_index}, {"count", s.shard_count}};
    j["jobs"] = s.jobs;
    j["threads_per_job"] = s.threads_per_job;
  }
  j["options"] = s.options;
  j["counts"] = counts;
  j["assets"] = assets;
  j["seconds"] = s.seconds;
  return j;
}

}  // namespace uvpress::batch
