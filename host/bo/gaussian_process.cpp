#include "bo/gaussian_process.h"

#include "bo/exp_neg.h"

#include <Eigen/Cholesky>
#include <nlopt.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace uvpress::bo {

namespace {
constexpr double kJitter = 1e-10;  // added to the diagonal: keeps duplicated points factorable
}  // namespace

// Matern 5/2 between the scaled point `xs` and each of the first n stored points, into
// out[0..n): squared distances first, then the kernel, each loop in vector lanes (exp_neg).
__attribute__((target_clones("avx2", "default")))
void GaussianProcess::kernel_row(const double* xs, size_t n, double* out) const {
  std::fill(out, out + n, 0.0);
  for (int d = 0; d < dim_; ++d) {  // dimension by dimension: the same sums, in lanes
    const double* col = xs_[size_t(d)].data();
    const double c = xs[d];
    for (size_t i = 0; i < n; ++i) {
      const double t = c - col[i];
      out[i] += t * t;
    }
  }
  const double s2 = signal2_;
  for (size_t i = 0; i < n; ++i) {
    const double r = std::sqrt(5.0 * out[i]);  // sqrt(5) r
    out[i] = s2 * (1 + r + r * r / 3) * exp_neg(r);
  }
}

GaussianProcess::GaussianProcess(int dim) : dim_(dim) {
  if (dim < 1 || dim > kMaxDim) throw std::invalid_argument("GaussianProcess: dimension must be 1..8");
  GpHyperparameters h;
  for (int d = 0; d < dim; ++d) h.log_length[size_t(d)] = std::log(0.3);
  set_hyper(h);
}

void GaussianProcess::set_hyper(const GpHyperparameters& h) {
  hyper_ = h;
  for (int d = 0; d < dim_; ++d) inv_length_[size_t(d)] = std::exp(-h.log_length[size_t(d)]);
  signal2_ = std::exp(2 * h.log_signal);
  noise2_ = std::exp(2 * h.log_noise);
  rescale();
  refactor();
}

void GaussianProcess::rescale() {
  const size_t n = y_.size();
  for (int d = 0; d < dim_; ++d) {
    xs_[size_t(d)].resize(n);
    for (size_t i = 0; i < n; ++i) xs_[size_t(d)][i] = x_[i * size_t(dim_) + size_t(d)] * inv_length_[size_t(d)];
  }
}

void GaussianProcess::solve_alpha() {
  const Eigen::Index n = Eigen::Index(y_.size());
  Eigen::VectorXd r(n);
  for (Eigen::Index i = 0; i < n; ++i) r(i) = (y_[size_t(i)] - y_mean_) / y_scale_;
  auto L = chol_.topLeftCorner(n, n).triangularView<Eigen::Lower>();
  L.solveInPlace(r);
  L.transpose().solveInPlace(r);
  alpha_ = r;
}

void GaussianProcess::refactor() {
  const Eigen::Index n = Eigen::Index(y_.size());
  Eigen::MatrixXd K(n, n);
  std::vector<double> row(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    double xs[kMaxDim];
    for (int d = 0; d < dim_; ++d) xs[d] = xs_[size_t(d)][size_t(i)];
    kernel_row(xs, size_t(i) + 1, row.data());
    for (Eigen::Index j = 0; j <= i; ++j) K(i, j) = row[size_t(j)];
  }
  K.diagonal().array() += noise2_ + kJitter;
  Eigen::LLT<Eigen::MatrixXd, Eigen::Lower> llt(K);
  factor_ok_ = llt.info() == Eigen::Success;
  chol_.resize(std::max<Eigen::Index>(n, 16), std::max<Eigen::Index>(n, 16));
  if (factor_ok_) {
    chol_.topLeftCorner(n, n) = llt.matrixL();
  } else {  // not positive definite for these hyperparameters: a usable diagonal stand-in
    chol_.setZero();
    for (Eigen::Index i = 0; i < n; ++i) chol_(i, i) = std::sqrt(std::max(K(i, i), kJitter));
  }
  solve_alpha();
}

void GaussianProcess::add(const double* x, double y) {
  const Eigen::Index n = Eigen::Index(y_.size());
  if (n == 0) y_mean_ = y, y_scale_ = 1;  // the first point sets the standardization until the next fit
  if (chol_.rows() < n + 1) {  // grow by doubling, keeping the factor
    Eigen::MatrixXd bigger = Eigen::MatrixXd::Zero(std::max<Eigen::Index>(16, 2 * n), std::max<Eigen::Index>(16, 2 * n));
    bigger.topLeftCorner(n, n) = chol_.topLeftCorner(n, n);
    chol_.swap(bigger);
  }
  double xs[kMaxDim];
  for (int d = 0; d < dim_; ++d) xs[d] = x[d] * inv_length_[size_t(d)];
  Eigen::VectorXd k(n);
  kernel_row(xs, size_t(n), k.data());
  chol_.topLeftCorner(n, n).triangularView<Eigen::Lower>().solveInPlace(k);
  chol_.block(n, 0, 1, n) = k.transpose();
  chol_(n, n) = std::sqrt(std::max(signal2_ + noise2_ + kJitter - k.squaredNorm(), kJitter));
  x_.insert(x_.end(), x, x + dim_);
  for (int d = 0; d < dim_; ++d) xs_[size_t(d)].push_back(xs[d]);
  y_.push_back(y);
  solve_alpha();
}

void GaussianProcess::predict(const double* x, double* mean, double* variance) const {
  predict(x, 1, mean, variance);
}

void GaussianProcess::predict(const double* x, size_t m, double* mean, double* variance) const {
  const Eigen::Index n = Eigen::Index(y_.size());
  if (n == 0) {
    for (size_t q = 0; q < m; ++q) mean[q] = 0, variance[q] = signal2_;
    return;
  }
  Eigen::MatrixXd ks(n, Eigen::Index(m));
  for (Eigen::Index q = 0; q < Eigen::Index(m); ++q) {
    double xs[kMaxDim];
    for (int d = 0; d < dim_; ++d) xs[d] = x[size_t(q) * size_t(dim_) + size_t(d)] * inv_length_[size_t(d)];
    kernel_row(xs, size_t(n), ks.col(q).data());
  }
  Eigen::VectorXd mu = ks.transpose() * alpha_;
  chol_.topLeftCorner(n, n).triangularView<Eigen::Lower>().solveInPlace(ks);  // v = L^-1 k*
  for (Eigen::Index q = 0; q < Eigen::Index(m); ++q) {
    double v = signal2_ - ks.col(q).squaredNorm();  // k(x, x) = signal^2 for a stationary kernel
    mean[q] = y_mean_ + y_scale_ * mu(q);
    variance[q] = std::max(v, 1e-12 * signal2_) * y_scale_ * y_scale_;
  }
}

double GaussianProcess::log_marginal_likelihood() const {
  const size_t n = y_.size();
  double fit = 0, logdet = 0;
  for (size_t i = 0; i < n; ++i) {
    fit += ((y_[i] - y_mean_) / y_scale_) * alpha_(Eigen::Index(i));
    logdet += std::log(chol_(Eigen::Index(i), Eigen::Index(i)));
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
