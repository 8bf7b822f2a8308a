#include "bo/gaussian_process.h"

#include <nlopt.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace uvpress::bo {

namespace {
constexpr double kJitter = 1e-10;  // added to the diagonal: keeps duplicated points factorable
}

GaussianProcess::GaussianProcess(int dim) : dim_(dim) {
  if (dim < 1 || dim > kMaxDim) throw std::invalid_argument("GaussianProcess: dimension must be 1..8");
  GpHyperparameters h;
  for (int d = 0; d < dim; ++d) h.log_length[size_t(d)] = std::log(0.3);
  set_hyper(h);
}

void GaussianProcess::set_hyper(const GpHyperparameters& h) {
  hyper_ = h;
  for (int d = 0; d < dim_; ++d) inv_length2_[size_t(d)] = std::exp(-2 * h.log_length[size_t(d)]);
  signal2_ = std::exp(2 * h.log_signal);
  noise2_ = std::exp(2 * h.log_noise);
  refactor();
}

double GaussianProcess::kernel(const double* a, const double* b) const {
  double r2 = 0;
  for (int d = 0; d < dim_; ++d) {
    double t = a[d] - b[d];
    r2 += t * t * inv_length2_[size_t(d)];
  }
  const double r = std::sqrt(5.0 * r2);  // sqrt(5) r
  return signal2_ * (1 + r + r * r / 3) * std::exp(-r);
}

void GaussianProcess::solve_alpha() {
  const size_t n = y_.size();
  alpha_.resize(n);
  for (size_t i = 0; i < n; ++i) {  // L z = y
    double s = (y_[i] - y_mean_) / y_scale_;
    for (size_t j = 0; j < i; ++j) s -= L(i, j) * alpha_[j];
    alpha_[i] = s / L(i, i);
  }
  for (size_t i = n; i-- > 0;) {  // L^T alpha = z
    double s = alpha_[i];
    for (size_t j = i + 1; j < n; ++j) s -= L(j, i) * alpha_[j];
    alpha_[i] = s / L(i, i);
  }
}

void GaussianProcess::refactor() {
  const size_t n = y_.size();
  chol_.assign(n * (n + 1) / 2, 0.0);
  factor_ok_ = true;
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j <= i; ++j) {
      double s = kernel(&x_[i * size_t(dim_)], &x_[j * size_t(dim_)]);
      if (i == j) s += noise2_ + kJitter;
      for (size_t k = 0; k < j; ++k) s -= L(i, k) * L(j, k);
      if (i == j) {
        if (s <= 0) factor_ok_ = false, s = kJitter;
        L(i, i) = std::sqrt(s);
      } else {
        L(i, j) = s / L(j, j);
      }
    }
  solve_alpha();
}

void GaussianProcess::add(const double* x, double y) {
  const size_t n = y_.size();
  x_.insert(x_.end(), x, x + dim_);
  y_.push_back(y);
  if (n == 0) {  // the first point sets the standardization until the next fit
    y_mean_ = y, y_scale_ = 1;
  }
  chol_.resize((n + 1) * (n + 2) / 2);
  double diag = kernel(x, x) + noise2_ + kJitter;
  for (size_t j = 0; j < n; ++j) {
    double s = kernel(x, &x_[j * size_t(dim_)]);
    for (size_t k = 0; k < j; ++k) s -= L(n, k) * L(j, k);
    L(n, j) = s / L(j, j);
    diag -= L(n, j) * L(n, j);
  }
  L(n, n) = std::sqrt(std::max(diag, kJitter));
  solve_alpha();
}

void GaussianProcess::predict(const double* x, double* mean, double* variance) const {
  const size_t n = y_.size();
  if (n == 0) {
    *mean = 0, *variance = signal2_;
    return;
  }
  double m = 0, v = kernel(x, x);
  // v = L^-1 k*, computed row by row; var = k(x,x) - |v|^2.
  double stack[128];
  std::vector<double> heap;
  double* w = stack;
  if (n > 128) heap.resize(n), w = heap.data();
  for (size_t i = 0; i < n; ++i) {
    double k = kernel(x, &x_[i * size_t(dim_)]);
    m += k * alpha_[i];
    double s = k;
    for (size_t j = 0; j < i; ++j) s -= L(i, j) * w[j];
    w[i] = s / L(i, i);
    v -= w[i] * w[i];
  }
  *mean = y_mean_ + y_scale_ * m;
  *variance = std::max(v, 1e-12 * signal2_) * y_scale_ * y_scale_;
}

double GaussianProcess::log_marginal_likelihood() const {
  const size_t n = y_.size();
  double fit = 0, logdet = 0;
  for (size_t i = 0; i < n; ++i) {
    fit += ((y_[i] - y_mean_) / y_scale_) * alpha_[i];
    logdet += std::log(L(i, i));
  }
  return -0.5 * fit - logdet - 0.5 * double(n) * std::log(2 * M_PI);
}

void GaussianProcess::fit(int max_evals) {
  const size_t n = y_.size();
  if (n < 2) return;
  double mean = 0, var = 0;
  for (double v : y_) mean += v;
  mean /= double(n);
  for (double v : y_) var += (v - mean) * (v - mean);
  y_mean_ = mean;
  y_scale_ = var > 0 ? std::sqrt(var / double(n)) : 1.0;

  // theta = (log lengths, log signal, log noise), boxed to sensible ranges.
  const unsigned p = unsigned(dim_) + 2;
  std::vector<double> theta(p), lo(p), hi(p);
  for (int d = 0; d < dim_; ++d)
    theta[size_t(d)] = hyper_.log_length[size_t(d)], lo[size_t(d)] = std::log(0.02), hi[size_t(d)] = std::log(5.0);
  theta[size_t(dim_)] = hyper_.log_signal, lo[size_t(dim_)] = std::log(0.1), hi[size_t(dim_)] = std::log(10.0);
  theta[size_t(dim_) + 1] = hyper_.log_noise, lo[size_t(dim_) + 1] = std::log(1e-5), hi[size_t(dim_) + 1] = std::log(0.3);
  for (unsigned i = 0; i < p; ++i) theta[i] = std::min(std::max(theta[i], lo[i]), hi[i]);

  auto unpack = [&](const std::vector<double>& t) {
    GpHyperparameters h;
    for (int d = 0; d < dim_; ++d) h.log_length[size_t(d)] = t[size_t(d)];
    h.log_signal = t[size_t(dim_)];
    h.log_noise = t[size_t(dim_) + 1];
    return h;
  };
  using Unpack = decltype(unpack);
  struct Ctx {
    GaussianProcess* gp;
    Unpack* to_hyper;
  } ctx{this, &unpack};
  nlopt::opt opt(nlopt::LN_BOBYQA, p);
  opt.set_lower_bounds(lo);
  opt.set_upper_bounds(hi);
  opt.set_maxeval(max_evals);
  opt.set_xtol_rel(1e-3);
  opt.set_max_objective(
      [](const std::vector<double>& t, std::vector<double>&, void* data) {
        auto* c = static_cast<Ctx*>(data);
        c->gp->set_hyper((*c->to_hyper)(t));
        double ll = c->gp->log_marginal_likelihood();
        return (std::isfinite(ll) && c->gp->factor_ok_) ? ll : -1e300;
      },
      &ctx);
  GpHyperparameters before = hyper_;
  set_hyper(before);
  double best_before = log_marginal_likelihood();
  double best = -1e300;
  try {
    opt.optimize(theta, best);
  } catch (const std::exception&) {
    best = -1e300;  // NLopt gave up (roundoff): keep what we had
  }
  set_hyper(best > best_before ? unpack(theta) : before);
}

}  // namespace uvpress::bo
