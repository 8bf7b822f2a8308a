// Bayesian optimization of an expensive function on [0,1]^d (Limbo/BayesOpt defaults):
// a space-filling initial design (scrambled Halton), then one proposal per round that
// maximizes an acquisition over quasi-random candidates plus a local refinement of the
// best few; GP hyperparameters refit on a schedule. The acquisition is the caller's: it
// sees the GP's posterior at a point, so structure known in closed form (a cost term,
// a feasibility threshold) can enter it without ever reaching the GP.
#pragma once

#include "bo/gaussian_process.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace uvpress::bo {

struct BoOptions {
  int dim = 2;
  int initial = 10;           // space-filling points before the GP guides
  int candidates = 96;        // quasi-random acquisition candidates per round
  int refine = 3;             // best candidates refined locally...
  int refine_steps = 8;       // ...by this many Gaussian perturbations each, twice
  double refine_sigma = 0.05;
  int fit_evals = 40;         // likelihood evaluations per hyperparameter refit
  uint64_t seed = 1;
};

// Value to maximize at x given the GP posterior mean and standard deviation there.
using Acquisition = std::function<double(const double* x, double mean, double sd)>;

class BayesOpt {
 public:
  explicit BayesOpt(const BoOptions& options);

  // Writes the next point to evaluate. Initial design first (in order), then acquisition.
  void propose(const Acquisition& acquisition, double* x);
  // Records an evaluation (z is what the GP models).
  void observe(const double* x, double z);
  // Overrides initial design point k (e.g. a known-feasible start).
  void set_initial_point(int k, const double* x);

  size_t evaluations() const { return gp_.size(); }
  const GaussianProcess& gp() const { return gp_; }

 private:
  BoOptions o_;
  GaussianProcess gp_;
  std::vector<double> design_;  // initial x, row by row
  uint64_t rng_;
  int next_fit_ = 0;
};

// Halton point `index` (>= 1) in `dim` <= 8 dimensions, Cranley-Patterson shifted by `shift`.
void halton(uint64_t index, int dim, const double* shift, double* out);

// Closed-form expected improvement below `best` for a minimized GP quantity.
double expected_improvement(double best, double mean, double sd);

// Standard normal density and distribution.
double normal_pdf(double z);
double normal_cdf(double z);

}  // namespace uvpress::bo
