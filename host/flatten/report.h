// What a flatten run reports: the summary fields shared by `uvpress flatten --report` and
// `uvpress bench flatten` (one JSON object per run), and the per-iteration log as CSV or
// JSON. Peak memory from the kernel's high-water mark (VmHWM), resettable between runs.
#pragma once

#include "flatten/flatten.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace uvpress::flatten {

// "bench":"flatten" is added by the benchmark; the fields here are the list:
// method, faces, N_c, eta, t_c_s, E_c, s_per_iter, flips, peak_rss_mb, plus detail.
nlohmann::ordered_json summary_json(const Result& r, Method method, size_t faces, size_t vertices);

struct LabelledLog {
  std::string label;  // chart name, empty for a single mesh
  const std::vector<IterationRecord>* log;
};
std::string log_csv(const std::vector<LabelledLog>& logs);
std::string log_json(const std::vector<LabelledLog>& logs);

// Peak resident set size of this process in MiB (0 when /proc is unavailable), and a
// reset of that peak to the current size (Linux: echo 5 > /proc/self/clear_refs).
double peak_rss_mb();
void reset_peak_rss();

// OpenMP threads the per-triangle loops use.
int thread_count();

}  // namespace uvpress::flatten
