// uvpress flatten: foldover-free, low-distortion parameterization of a disk-topology mesh
// by the progressive method of Liu, Ye, Ni, Fu, "Progressive Parameterizations" (SIGGRAPH
// 2018), with its competitors SLIM (Rabinovich et al. 2017), CM (Shtengel et al. 2017),
// P-CM and HYBRID (paper §4.2) behind one call. Every method starts from the same Tutte
// embedding and minimizes the same symmetric Dirichlet energy E(M, M^p) of problem (5).
#pragma once

#include "core/mesh.h"

#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace uvpress::flatten {

enum class Method {
  Progressive,  // progressive references, hybrid SLIM -> CM solver (the paper's "Ours")
  Slim,         // SLIM on problem (5)
  Cm,           // composite majorization on problem (5)
  PCm,          // progressive references, CM solver only
  Hybrid,       // no progressive references, SLIM -> CM switching of §3.5
};
const char* to_string(Method m);
std::optional<Method> parse_method(const std::string& name);
std::vector<Method> all_methods();

// A mesh that is not a topological disk, or unusable geometry. The message says why.
class FlattenError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Why the iterations ended. The first three are convergence (Result::converged), the last
// two failure (Result::failed(): the UVs are not the method's result - the last accepted
// iterate, flip-free, but nothing to ship); MaxIterations is neither: the budget ran out on
// a valid map that had not converged.
enum class StopReason {
  RelativeChange,   // e_n < relative_tolerance in the final phase (problem (5))
  GradientNorm,     // |grad E| < gradient_tolerance in the final phase
  StalledAtFloor,   // final phase: no step along a descent direction lowers E any more
                    // (Armijo, 60 halvings): E is at its floating-point floor
  MaxIterations,    // max_iterations linear solves
  LineSearchFailed, // the step gave no descent direction (grad . d not < 0 or not finite)
                    // or no room to move (maximal non-inverting step 0)
  FactorizationFailed,  // CHOLMOD could not factorize the system (not positive definite,
                        // non-finite entries, out of memory); Result::failure says which
};
// "relative change", "gradient norm", "stalled at floor", "max iterations",
// "line search failed", "factorization failed".
const char* to_string(StopReason r);
bool is_convergence(StopReason r);  // RelativeChange, GradientNorm, StalledAtFloor
bool is_failure(StopReason r);      // LineSearchFailed, FactorizationFailed

// One iteration (= one linear solve) of the solver.
struct IterationRecord {
  int iteration = 0;           // 1-based
  const char* phase = "";      // "p-slim", "p-cm" (progressive references), "slim", "cm" (problem (5))
  double energy = 0;           // E(M, M^p) / |M| after the step: the paper's normalized energy
  double relative_change = 0;  // e_n, eq. (11)
  double max_distortion = 0;   // max_i D(f_i, f_i^p)
  double fraction_bounded = 0; // fraction of triangles with D(f_i, f_i^p) <= K
  double t_com = 1;            // eq. (10); 1 when the references are the ideal triangles
  double step = 0, max_step = 0;  // accepted step, maximal non-inverting step
  double gradient_norm = 0;    // of the objective that was minimized, before the step
  double objective_before = 0, objective_after = 0;  // that objective ((4) or (5)) around the step
  size_t inverted = 0;         // triangles with det J <= 0 after the step (always 0)
  bool factorized = false;     // the step factorized its system (else PCG on an earlier factor)
  int pcg_iterations = 0;      // PCG iterations the step spent (a failed attempt included)
  // Seconds: per-triangle energy, gradient, SVD and references; per-triangle Hessian
  // proxies and sparse assembly; numeric factorization; triangular solves; line search.
  double t_gradient = 0, t_assembly = 0, t_factorization = 0, t_solve = 0, t_line_search = 0, t_total = 0;
};

struct Options {
  Method method = Method::Progressive;
  double K = 60;               // distortion bound on D = (|J|^2 + |J^-1|^2)/4, §3.6
  int max_iterations = 5000;
  double relative_tolerance = 1e-6;  // stop when e_n < this ...
  double gradient_tolerance = 1e-6;  // ... or the gradient norm is below this
  double eta_epsilon = 0.01;         // eq. (12)
  std::function<void(const IterationRecord&)> on_iteration;  // called after every iteration
  // Test hook: the n-th numeric factorization (1-based; 0 = none) sees the system negated,
  // so CHOLMOD fails on it as on a matrix that is not positive definite.
  int test_break_factorization = 0;
  // Test hook: PCG iterations a solve may spend on an earlier factorization before
  // refactorizing; -1 keeps the budget the sparse system derives from the mesh (0 on small
  // meshes), a positive value forces the reuse path on a small test mesh.
  int test_pcg_budget = -1;
};

struct Result {
  // u v per vertex of the input mesh, scaled so that the UV area equals the 3-D area.
  // Vertices no triangle uses get (0, 0).
  std::vector<double> uv;
  int iterations = 0;           // N_c: linear solves
  int factorizations = 0;       // numeric factorizations among them (the rest: PCG, see sparse_system.h)
  long pcg_iterations = 0;
  StopReason stop = StopReason::MaxIterations;
  bool converged = false;       // is_convergence(stop)
  std::string stop_reason;      // to_string(stop): what the reports carry ("stop")
  std::string failure;          // when failed(): the reason in words, e.g. "factorization failed:
                                // matrix not positive definite (CHOLMOD)"; "" otherwise
  bool failed() const { return is_failure(stop); }
  int eta = 0;                  // eq. (12)
  double initial_energy = 0;    // E/|M| of the Tutte embedding
  double energy = 0;            // E_c = E(M, M^p_c) / |M|
  double max_distortion = 0;
  double seconds = 0;           // t_c: the iterations, without the Tutte initialization
  double init_seconds = 0;      // Tutte embedding and set-up
  size_t flips = 0;             // triangles with det J <= 0 in `uv` (checked independently)
  size_t degenerate_references = 0;  // 3-D triangles too thin to define a reference (see tutte.h)
  std::vector<IterationRecord> log;
};

// Throws FlattenError when the mesh is not a single disk (see disk_topology.h).
Result flatten(const Mesh& mesh, const Options& options = {});

// One chart of a real asset (a glTF chart has holes: eyes, mouths, cut-outs): every
// boundary loop but the longest closed for the solve by a fan to a temporary vertex at its
// centroid (disk_topology.h fill_holes), flattened, the temporary vertices dropped again
// (`result.uv` has 2 values per vertex of `chart`). Throws FlattenError when the chart is
// no disk even then (a handle, a non-manifold vertex, a degenerate Tutte embedding); a
// solve that fails is in the result (invalid_reason says so).
struct ChartResult {
  Result result;
  size_t filled_holes = 0;  // boundary loops closed for the solve
};
ChartResult flatten_chart(const Mesh& chart, const Options& options = {});

// Why `r` is not a valid map to write, in one phrase for an error line ("" when it is one):
// a failed solve (r.failure), flipped triangles (r.flips), or non-finite UVs. A stall at
// the floor or the iteration limit on a flip-free, finite map is a valid map.
std::string invalid_reason(const Result& r);

// Triangles whose UV image has non-positive signed area (counter-clockwise = positive).
size_t count_flips(const std::vector<uint32_t>& triangles, const std::vector<double>& uv);

}  // namespace uvpress::flatten
