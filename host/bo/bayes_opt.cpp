#include "bo/bayes_opt.h"

#include <algorithm>
#include <cmath>

namespace uvpress::bo {

namespace {

// splitmix64: a tiny, seedable generator whose stream depends only on the seed.
uint64_t next(uint64_t& s) {
  uint64_t z = (s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
double uniform(uint64_t& s) { return double(next(s) >> 11) * 0x1.0p-53; }
double gaussian(uint64_t& s) {
  double u = std::max(uniform(s), 1e-300), v = uniform(s);
  return std::sqrt(-2 * std::log(u)) * std::cos(2 * M_PI * v);
}

// Refits after these many observations: often early, when the model changes most.
bool refit_now(size_t n) {
  static const size_t schedule[] = {6, 10, 14, 20, 28, 38, 50, 65, 80, 95};
  return std::find(std::begin(schedule), std::end(schedule), n) != std::end(schedule);
}

}  // namespace

double normal_pdf(double z) { return std::exp(-0.5 * z * z) / std::sqrt(2 * M_PI); }
double normal_cdf(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

double expected_improvement(double best, double mean, double sd) {
  if (sd <= 0) return std::max(best - mean, 0.0);
  double z = (best - mean) / sd;
  return (best - mean) * normal_cdf(z) + sd * normal_pdf(z);
}

void halton(uint64_t index, int dim, const double* shift, double* out) {
  static const int primes[kMaxDim] = {2, 3, 5, 7, 11, 13, 17, 19};
  for (int d = 0; d < dim; ++d) {
    double f = 1, r = 0;
    for (uint64_t i = index; i > 0; i /= uint64_t(primes[d])) {
      f /= primes[d];
      r += f * double(i % uint64_t(primes[d]));
    }
    r += shift ? shift[d] : 0.0;
    out[d] = r - std::floor(r);
  }
}

BayesOpt::BayesOpt(const BoOptions& o) : o_(o), gp_(o.dim), rng_(o.seed * 0x2545F4914F6CDD1Dull + 1) {
  // Initial design: a randomly shifted Halton set.
  double shift[kMaxDim];
  for (int d = 0; d < o.dim; ++d) shift[d] = uniform(rng_);
  design_.resize(size_t(o.initial) * size_t(o.dim));
  for (int k = 0; k < o.initial; ++k) halton(uint64_t(k) + 1, o.dim, shift, &design_[size_t(k) * size_t(o.dim)]);
}

void BayesOpt::set_initial_point(int k, const double* x) {
  std::copy(x, x + o_.dim, design_.begin() + long(k) * o_.dim);
}

void BayesOpt::observe(const double* x, double z) {
  gp_.add(x, z);
  if (refit_now(gp_.size())) gp_.fit(o_.fit_evals);
}

void BayesOpt::propose(const Acquisition& acq, double* x) {
  const size_t n = gp_.size();
  const int dim = o_.dim;
  if (n < size_t(o_.initial)) {
    std::copy(&design_[n * size_t(dim)], &design_[n * size_t(dim)] + dim, x);
    return;
  }
  auto score = [&](const double* p) {
    double mean, var;
    gp_.predict(p, &mean, &var);
    return acq(p, mean, std::sqrt(var));
  };
  // Quasi-random candidates, shifted anew every round.
  double shift[kMaxDim];
  for (int d = 0; d < dim; ++d) shift[d] = uniform(rng_);
  struct Scored {
    double value;
    std::array<double, kMaxDim> p;
  };
  std::vector<Scored> best;  // the top `refine`, best first
  auto consider = [&](const double* p) {
    Scored s{score(p), {}};
    std::copy(p, p + dim, s.p.begin());
    if (int(best.size()) < std::max(o_.refine, 1) || s.value > best.back().value) {
      best.push_back(s);
      std::sort(best.begin(), best.end(), [](const Scored& a, const Scored& b) { return a.value > b.value; });
      if (int(best.size()) > std::max(o_.refine, 1)) best.pop_back();
    }
  };
  double p[kMaxDim];
  for (int k = 0; k < o_.candidates; ++k) {
    halton(uint64_t(k) + 1 + 7919 * n, dim, shift, p);
    consider(p);
  }
  // Local refinement: Gaussian steps around the best few, kept when they improve.
  const size_t seeds = best.size();
  for (size_t s = 0; s < seeds; ++s) {
    Scored cur = best[s];
    for (int step = 0; step < o_.refine_steps; ++step) {
      double q[kMaxDim];
      for (int d = 0; d < dim; ++d)
        q[d] = std::min(1.0, std::max(0.0, cur.p[size_t(d)] + o_.refine_sigma * gaussian(rng_)));
      double v = score(q);
      if (v > cur.value) {
        cur.value = v;
        std::copy(q, q + dim, cur.p.begin());
      }
    }
    if (cur.value > best[0].value) best[0] = cur;
  }
  std::copy(best[0].p.begin(), best[0].p.begin() + dim, x);
}

}  // namespace uvpress::bo
