// The driver: Algorithm 1 of the paper with the practical rules of §3.5-3.6, and the
// competitors it is compared with, on one code path.
//
//   progressive loop (Progressive, P-CM): while fewer than 99% of the triangles have
//     D(f_i, f_i^p) <= K, e_n >= 1e-2 and t_com < 0.999: t_com (eq. 10), references
//     (eq. 6), one step of problem (4) with uniform weights 1/N_f.
//   final phase: problem (5) with the ideal references and area weights until
//     e_n < 1e-6 or |grad E| < 1e-6 (or max_iterations).
//   solver: SLIM while fewer than 99% of the triangles have D <= K and e_n >= 0.1
//     (Progressive, Hybrid; once switched, CM stays); CM throughout for CM and P-CM; SLIM
//     throughout for SLIM.
// e_n (eq. 11) is the relative change of the true energy E(M, M^p), 1000 before the first
// iteration. The mesh is scaled to area 1, so E = E/|M| = the paper's E_c at convergence.
#include "flatten/flatten.h"

#include "core/parallel.h"
#include "core/stopwatch.h"
#include "flatten/disk_topology.h"
#include "flatten/problem.h"
#include "flatten/progressive.h"
#include "flatten/solver.h"
#include "flatten/tutte.h"
#include "solve/triangle_energy.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace uvpress::flatten {

const char* to_string(Method m) {
  switch (m) {
    case Method::Progressive: return "progressive";
    case Method::Slim: return "slim";
    case Method::Cm: return "cm";
    case Method::PCm: return "p-cm";
    case Method::Hybrid: return "hybrid";
  }
  return "?";
}

std::optional<Method> parse_method(const std::string& name) {
  for (Method m : all_methods())
    if (name == to_string(m)) return m;
  return std::nullopt;
}

const char* to_string(StopReason r) {
  switch (r) {
    case StopReason::RelativeChange: return "relative change";
    case StopReason::GradientNorm: return "gradient norm";
    case StopReason::StalledAtFloor: return "stalled at floor";
    case StopReason::MaxIterations: return "max iterations";
    case StopReason::LineSearchFailed: return "line search failed";
    case StopReason::FactorizationFailed: return "factorization failed";
  }
  return "?";
}

bool is_convergence(StopReason r) {
  return r == StopReason::RelativeChange || r == StopReason::GradientNorm || r == StopReason::StalledAtFloor;
}

bool is_failure(StopReason r) { return r == StopReason::LineSearchFailed || r == StopReason::FactorizationFailed; }

std::string invalid_reason(const Result& r) {
  if (r.failed()) return r.failure.empty() ? to_string(r.stop) : r.failure;
  if (r.flips) return std::to_string(r.flips) + " flipped triangles in the UVs";
  for (double x : r.uv)
    if (!std::isfinite(x)) return "non-finite UVs";
  return "";
}

ChartResult flatten_chart(const Mesh& chart, const Options& options) {
  const FilledHoles filled = fill_holes(chart.positions, chart.triangles);
  Mesh closed;
  closed.positions = filled.positions;
  closed.triangles = filled.triangles;
  ChartResult out;
  out.result = flatten(closed, options);
  out.result.uv.resize(2 * chart.vertex_count());  // the temporary vertices go
  out.filled_holes = filled.filled_loops;
  return out;
}

std::vector<Method> all_methods() { return {Method::Progressive, Method::Slim, Method::Cm, Method::PCm, Method::Hybrid}; }

size_t count_flips(const std::vector<uint32_t>& tris, const std::vector<double>& uv) {
  size_t flips = 0;
  for (size_t t = 0; t < tris.size() / 3; ++t) {
    const double* a = &uv[2 * size_t(tris[3 * t])];
    const double* b = &uv[2 * size_t(tris[3 * t + 1])];
    const double* c = &uv[2 * size_t(tris[3 * t + 2])];
    const double det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    flips += !(det > 0);
  }
  return flips;
}

namespace {

// The true distortion of every triangle (relative to the ideal references).
struct Analysis {
  double energy = 0, max_distortion = 0, fraction_bounded = 0;
  size_t inverted = 0;  // D = +inf: det J <= 0
  std::vector<double> J, D;  // 4 and 1 per triangle
};

void analyze(const Problem& p, const std::vector<double>& uv, const std::vector<double>& weights, double K,
             Analysis& a) {
  const long nt = long(p.triangle_count());
  a.J.resize(4 * size_t(nt));
  a.D.resize(size_t(nt));
  std::vector<double> e(static_cast<size_t>(nt));
  double max_d = 0;
  long bounded = 0, inverted = 0;
#pragma omp parallel for schedule(static) if (worth_threads(nt)) reduction(max : max_d) reduction(+ : bounded, inverted)
  for (long t = 0; t < nt; ++t) {
    double* J = &a.J[4 * size_t(t)];
    jacobian(&p.ideal[4 * size_t(t)], uv.data(), &p.triangles[3 * size_t(t)], J);
    const double d = solve::distortion(J);
    a.D[size_t(t)] = d;
    e[size_t(t)] = weights[size_t(t)] * d;
    max_d = std::max(max_d, d);
    bounded += d <= K;
    inverted += !std::isfinite(d);
  }
  a.energy = fixed_order_sum(size_t(nt), e.data());
  a.max_distortion = max_d;
  a.fraction_bounded = double(bounded) / double(nt);
  a.inverted = size_t(inverted);
}

}  // namespace

Result flatten(const Mesh& mesh, const Options& o) {
  const Stopwatch start;
  for (double x : mesh.positions)
    if (!std::isfinite(x)) throw FlattenError("non-finite vertex coordinate");
  DiskTopology topo = check_disk(mesh.triangles, mesh.vertex_count());
  std::vector<double> positions(3 * topo.used_vertices.size());
  for (size_t i = 0; i < topo.used_vertices.size(); ++i)
    for (int k = 0; k < 3; ++k) positions[3 * i + size_t(k)] = mesh.positions[3 * size_t(topo.used_vertices[i]) + size_t(k)];
  const Problem p = make_problem(positions, topo.triangles);
  const size_t nt = p.triangle_count();

  Solver solver(p);  // first: the Tutte solve takes its elimination order
  solver.break_factorization(o.test_break_factorization);
  if (o.test_pcg_budget >= 0) solver.set_pcg_budget(o.test_pcg_budget);
  const std::vector<uint32_t> order = solver.vertex_order();
  std::vector<double> uv = tutte_embedding(p.vertex_count, p.triangles, topo.boundary, 1.0, &order);
  if (size_t bad = count_flips(p.triangles, uv))
    throw FlattenError("the Tutte embedding degenerates " + std::to_string(bad) +
                       " triangles in floating point (the mesh is too irregular)");
  const std::vector<double> area_w = area_weights(p);
  const std::vector<double> uniform_w(nt, 1.0 / double(nt));

  Result r;
  r.degenerate_references = p.degenerate;
  Analysis a;
  analyze(p, uv, area_w, o.K, a);
  r.initial_energy = a.energy;
  r.init_seconds = start.seconds();
  const Stopwatch loop;

  const bool progressive = o.method == Method::Progressive || o.method == Method::PCm;
  bool in_progressive = progressive;
  bool slim = o.method == Method::Slim || o.method == Method::Progressive || o.method == Method::Hybrid;
  double e_n = 1000;
  std::vector<double> ref;
  r.stop = StopReason::MaxIterations;
  for (int it = 1; it <= o.max_iterations; ++it) {
    const Stopwatch clock;
    double t_com = 1;
    if (in_progressive) {
      t_com = common_parameter(a.J, a.D, o.K);
      if (a.fraction_bounded >= 0.99 || e_n < 1e-2 || t_com >= 0.999) in_progressive = false;
    }
    if (slim && o.method != Method::Slim && (a.fraction_bounded >= 0.99 || e_n < 0.1)) slim = false;
    if (in_progressive) progressive_references(p.ideal, a.J, t_com, ref);
    else t_com = 1;
    const double t_reference = clock.seconds();

    StepStats s = solver.step(uv, in_progressive ? ref : p.ideal, in_progressive ? uniform_w : area_w,
                              slim ? Proxy::Slim : Proxy::Cm, in_progressive ? 0.0 : o.gradient_tolerance);
    r.factorizations += s.factorized;
    r.pcg_iterations += s.pcg_iterations;
    if (s.below_gradient_tolerance) {
      r.stop = StopReason::GradientNorm;
      break;
    }
    if (s.factorization_failed) {  // a solver failure in either phase: nothing to fall back on
      r.stop = StopReason::FactorizationFailed;
      r.failure = s.failure;
      break;
    }
    if (s.line_search_failed) {
      if (in_progressive) {  // the references gave nothing more: go on with problem (5)
        in_progressive = false;
        --it;
        continue;
      }
      if (s.no_decrease) {  // a descent direction that gives no decrease: E is at its floor
        r.stop = StopReason::StalledAtFloor;
      } else {
        r.stop = StopReason::LineSearchFailed;
        char detail[160];
        std::snprintf(detail, sizeof detail, "line search failed: no descent direction (gradient norm %.3g, maximal step %.3g)",
                      s.gradient_norm, s.max_step);
        r.failure = detail;
      }
      break;
    }
    const Stopwatch t_analyze;
    const double before = a.energy;
    analyze(p, uv, area_w, o.K, a);
    e_n = std::abs(before - a.energy) / a.energy;

    IterationRecord rec;
    rec.iteration = it;
    rec.phase = in_progressive ? (slim ? "p-slim" : "p-cm") : (slim ? "slim" : "cm");
    rec.energy = a.energy;
    rec.relative_change = e_n;
    rec.max_distortion = a.max_distortion;
    rec.fraction_bounded = a.fraction_bounded;
    rec.t_com = t_com;
    rec.step = s.step, rec.max_step = s.max_step;
    rec.gradient_norm = s.gradient_norm;
    rec.objective_before = s.energy_before, rec.objective_after = s.energy_after;
    rec.inverted = a.inverted;
    rec.factorized = s.factorized, rec.pcg_iterations = s.pcg_iterations;
    rec.t_gradient = s.t_gradient + t_reference + t_analyze.seconds();
    rec.t_assembly = s.t_assembly, rec.t_factorization = s.t_factorization, rec.t_solve = s.t_solve;
    rec.t_line_search = s.t_line_search;
    rec.t_total = clock.seconds();
    r.log.push_back(rec);
    r.iterations = it;
    if (o.on_iteration) o.on_iteration(rec);
    if (!in_progressive && e_n < o.relative_tolerance) {
      r.stop = StopReason::RelativeChange;
      break;
    }
  }
  r.converged = is_convergence(r.stop);
  r.stop_reason = to_string(r.stop);
  r.seconds = loop.seconds();
  r.energy = a.energy;
  r.max_distortion = a.max_distortion;
  r.eta = r.iterations;
  for (const auto& rec : r.log)
    if ((rec.energy - r.energy) / r.energy <= o.eta_epsilon) {
      r.eta = rec.iteration;
      break;
    }

  // Back to the input numbering and scale (UV area = 3-D area).
  r.uv.assign(2 * mesh.vertex_count(), 0.0);
  for (size_t i = 0; i < topo.used_vertices.size(); ++i) {
    r.uv[2 * size_t(topo.used_vertices[i])] = uv[2 * i] / p.scale;
    r.uv[2 * size_t(topo.used_vertices[i]) + 1] = uv[2 * i + 1] / p.scale;
  }
  r.flips = count_flips(mesh.triangles, r.uv);
  return r;
}

}  // namespace uvpress::flatten
