// One descent step of the symmetric Dirichlet objective sum_i w_i D(P_i Rinv_i) - problem
// (4) with progressive references and uniform weights, or problem (5) with the ideal
// references and area weights - by SLIM or CM: per-triangle gradient and 4x4 Hessian
// proxy (OpenMP, static schedule), gather into the fixed sparse pattern, CHOLMOD numeric
// factorization and solve (or PCG on an earlier factorization, see sparse_system.h), then
// the flip-free line search. Paper §3.5-3.6: one step per
// reference update; the iteration count N_c is the number of linear solves.
#pragma once

#include "flatten/problem.h"
#include "solve/sparse_system.h"

#include <vector>

namespace uvpress::flatten {

enum class Proxy { Slim, Cm };

struct StepStats {
  double energy_before = 0, energy_after = 0;
  double gradient_norm = 0;
  double step = 0, max_step = 0;
  bool below_gradient_tolerance = false;  // no step taken
  bool line_search_failed = false;        // no step taken: any of the three below
  bool no_decrease = false;     // a descent direction along which no step lowered the objective (60
                                // halvings from a0 > 0): the floating-point floor
  bool not_descent = false;     // the solve gave no descent direction (grad . d not < 0, NaN) or no
                                // room to move (maximal step 0)
  bool factorization_failed = false;  // the linear system could not be factorized (see failure)
  const char* failure = "";     // solve::SparseSystem::failure() when factorization_failed
  bool factorized = false;      // the step factorized its system (else PCG on an old factor)
  int pcg_iterations = 0;
  double t_gradient = 0, t_assembly = 0, t_factorization = 0, t_solve = 0, t_line_search = 0;
};

class Solver {
 public:
  explicit Solver(const Problem& problem);

  // Objective at uv (+inf when a triangle is inverted or degenerate).
  double energy(const std::vector<double>& uv, const std::vector<double>& ref, const std::vector<double>& w);
  // Gradient of the objective (2 per vertex), for tests.
  void gradient(const std::vector<double>& uv, const std::vector<double>& ref, const std::vector<double>& w,
                std::vector<double>& grad);
  // One iteration: moves uv (never through an inversion).
  StepStats step(std::vector<double>& uv, const std::vector<double>& ref, const std::vector<double>& w, Proxy proxy,
                 double gradient_tolerance);

  size_t nonzeros() const { return system_.nonzeros(); }
  // See solve::SparseSystem::vertex_order.
  std::vector<uint32_t> vertex_order() const { return system_.vertex_order(); }
  // Test hook: see solve::SparseSystem::set_pcg_budget.
  void set_pcg_budget(int iterations) { system_.set_pcg_budget(iterations); }
  // Test hook: see solve::SparseSystem::break_factorization.
  void break_factorization(int n) { system_.break_factorization(n); }

 private:
  const Problem& p_;
  solve::SparseSystem system_;
  std::vector<double> per_triangle_, grad6_, hess21_, grad_, dir_;
};

}  // namespace uvpress::flatten
