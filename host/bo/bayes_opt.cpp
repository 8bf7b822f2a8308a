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
  static const size_t schedule[] = {10, 16, 25, 38, 55, 80};
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

namespace {

// The radical inverse of i in base P, digit by digit. P is a template argument so that the
// divisions are by constants (a multiply and a shift): with P read from a table they were
// most of propose()'s own time.
template <uint64_t P>
double radical_inverse(uint64_t i) {
  double f = 1, r = 0;
  for (; i > 0; i /= P) {
    f /= double(P);
    r += f * double(i % P);
  }
  return r;
}

}  // namespace

void halton(uint64_t index, int dim, const double* shift, double* out) {
  for (int d = 0; d < dim; ++d) {
    double r = 0;
    switch (d) {  // the first kMaxDim primes
      case 0: r = radical_inverse<2>(index); break;
      case 1: r = radical_inverse<3>(index); break;
      case 2: r = radical_inverse<5>(index); break;
      case 3: r = radical_inverse<7>(index); break;
      case 4: r = radical_inverse<11>(index); break;
      case 5: r = radical_inverse<13>(index); break;
      case 6: r = radical_inverse<17>(index); break;
      default: r = radical_inverse<19>(index); break;
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
  // Scores a batch of points with one GP prediction (one triangular solve for all).
  std::vector<double> mean, var;
  auto score = [&](const std::vector<double>& pts, std::vector<double>& out) {
    const size_t m = pts.size() / size_t(dim);
    mean.resize(m), var.resize(m), out.resize(m);
    gp_.predict(pts.data(), m, mean.data(), var.data());
    for (size_t q = 0; q < m; ++q) out[q] = acq(&pts[q * size_t(dim)], mean[q], std::sqrt(var[q]));
  };
  // The `keep` best of a scored batch, best first (ties: the earlier point).
  auto top = [&](const std::vector<double>& values, size_t keep) {
    std::vector<size_t> order(values.size());
    for (size_t q = 0; q < order.size(); ++q) order[q] = q;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return values[a] > values[b]; });
    order.resize(std::min(keep, order.size()));
    return order;
  };

  // Quasi-random candidates, shifted anew every round.
  double shift[kMaxDim];
  for (int d = 0; d < dim; ++d) shift[d] = uniform(rng_);
  std::vector<double> pts(size_t(o_.candidates) * size_t(dim)), values;
  for (int k = 0; k < o_.candidates; ++k) halton(uint64_t(k) + 1 + 7919 * n, dim, shift, &pts[size_t(k) * size_t(dim)]);
  score(pts, values);
  std::vector<size_t> seeds = top(values, size_t(std::max(o_.refine, 1)));
  std::vector<double> best_p(&pts[seeds[0] * size_t(dim)], &pts[seeds[0] * size_t(dim)] + dim);
  double best_v = values[seeds[0]];
  std::vector<std::vector<double>> centres;
  for (size_t s : seeds) centres.emplace_back(&pts[s * size_t(dim)], &pts[s * size_t(dim)] + dim);

  // Local refinement in two batched passes: Gaussian steps around the best few, then
  // finer steps around the best of all.
  for (int pass = 0; pass < 2; ++pass) {
    const double sigma = pass == 0 ? o_.refine_sigma : o_.refine_sigma / 4;
    std::vector<double> local;
    for (const auto& c : centres)
      for (int step = 0; step < o_.refine_steps; ++step)
        for (int d = 0; d < dim; ++d)
          local.push_back(std::min(1.0, std::max(0.0, c[size_t(d)] + sigma * gaussian(rng_))));
    score(local, values);
    size_t b = top(values, 1)[0];
    if (values[b] > best_v) {
      best_v = values[b];
      best_p.assign(&local[b * size_t(dim)], &local[b * size_t(dim)] + dim);
    }
    centres = {best_p};
  }
  std::copy(best_p.begin(), best_p.end(), x);
}

}  // namespace uvpress::bo
