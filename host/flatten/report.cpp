#include "flatten/report.h"

#include <cstdio>
#include <omp.h>
#include <fstream>
#include <sstream>

namespace uvpress::flatten {

nlohmann::ordered_json summary_json(const Result& r, Method method, size_t faces, size_t vertices) {
  nlohmann::ordered_json j;
  j["method"] = to_string(method);
  j["faces"] = faces;
  j["vertices"] = vertices;
  j["N_c"] = r.iterations;
  j["eta"] = r.eta;
  j["t_c_s"] = r.seconds;
  j["E_c"] = r.energy;
  j["s_per_iter"] = r.iterations ? r.seconds / r.iterations : 0.0;
  j["flips"] = r.flips;
  j["peak_rss_mb"] = peak_rss_mb();
  j["converged"] = r.converged;
  j["stop"] = r.stop_reason;
  if (!r.failure.empty()) j["failure"] = r.failure;
  j["E_init"] = r.initial_energy;
  j["max_distortion"] = r.max_distortion;
  j["init_s"] = r.init_seconds;
  j["degenerate_references"] = r.degenerate_references;
  double tg = 0, ta = 0, tf = 0, ts = 0, tl = 0;
  for (const auto& rec : r.log)
    tg += rec.t_gradient, ta += rec.t_assembly, tf += rec.t_factorization, ts += rec.t_solve, tl += rec.t_line_search;
  j["factorizations"] = r.factorizations;
  j["pcg_iterations"] = r.pcg_iterations;
  j["seconds"] = {{"gradient", tg}, {"assembly", ta}, {"factorization", tf}, {"solve", ts}, {"line_search", tl}};
  int progressive = 0, slim = 0;
  for (const auto& rec : r.log) {
    std::string phase = rec.phase;
    progressive += phase.rfind("p-", 0) == 0;
    slim += phase == "slim" || phase == "p-slim";
  }
  j["progressive_iterations"] = progressive;
  j["slim_iterations"] = slim;
  return j;
}

namespace {
const char* kColumns[] = {"iteration", "phase", "energy", "relative_change", "max_distortion", "fraction_bounded",
                          "t_com", "step", "max_step", "gradient_norm", "t_gradient", "t_assembly",
                          "t_factorization", "t_solve", "t_line_search", "t_total", "factorized", "pcg_iterations"};

nlohmann::ordered_json record_json(const IterationRecord& r) {
  return {{"iteration", r.iteration}, {"phase", r.phase},
          {"energy", r.energy},       {"relative_change", r.relative_change},
          {"max_distortion", r.max_distortion}, {"fraction_bounded", r.fraction_bounded},
          {"t_com", r.t_com},         {"step", r.step},
          {"max_step", r.max_step},   {"gradient_norm", r.gradient_norm},
          {"t_gradient", r.t_gradient}, {"t_assembly", r.t_assembly},
          {"t_factorization", r.t_factorization}, {"t_solve", r.t_solve},
          {"t_line_search", r.t_line_search}, {"t_total", r.t_total},
          {"factorized", r.factorized}, {"pcg_iterations", r.pcg_iterations}};
}
}  // namespace

std::string log_csv(const std::vector<LabelledLog>& logs) {
  std::ostringstream out;
  out << "chart";
  for (const char* c : kColumns) out << ',' << c;
  out << '\n';
  char buf[512];
  for (const auto& l : logs)
    for (const auto& r : *l.log) {
      std::snprintf(buf, sizeof buf, "%s,%d,%s,%.17g,%.6g,%.9g,%.6f,%.9g,%.9g,%.9g,%.6g,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%d,%d\n",
                    l.label.c_str(), r.iteration, r.phase, r.energy, r.relative_change, r.max_distortion,
                    r.fraction_bounded, r.t_com, r.step, r.max_step, r.gradient_norm, r.t_gradient, r.t_assembly,
                    r.t_factorization, r.t_solve, r.t_line_search, r.t_total, int(r.factorized), r.pcg_iterations);
      out << buf;
    }
  return out.str();
}

std::string log_json(const std::vector<LabelledLog>& logs) {
  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  for (const auto& l : logs) {
    nlohmann::ordered_json chart;
    if (!l.label.empty()) chart["chart"] = l.label;
    chart["iterations"] = nlohmann::ordered_json::array();
    for (const auto& r : *l.log) chart["iterations"].push_back(record_json(r));
    out.push_back(chart);
  }
  return (logs.size() == 1 ? out[0] : out).dump(1) + "\n";
}

double peak_rss_mb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;  // kB
  return 0;
}

void reset_peak_rss() {
  std::ofstream out("/proc/self/clear_refs");
  out << "5";
}

int thread_count() { return omp_get_max_threads(); }

}  // namespace uvpress::flatten
