// Gaussian-process regression for Bayesian optimization in a unit box [0,1]^d, d <= 8:
// Matern 5/2 kernel with ARD length scales, a noise term, hyperparameters by maximum
// marginal likelihood (NLopt BOBYQA on log-parameters), and a Cholesky factor extended
// row by row as points arrive (O(n^2) per point) between refits. Predictions come in
// batches: one triangular solve for many points (Eigen's blocked, vectorized TRSM).
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <vector>

namespace uvpress::bo {

constexpr int kMaxDim = 8;

struct GpHyperparameters {
  std::array<double, kMaxDim> log_length{};  // ARD length scales (unit-box coordinates)
  double log_signal = 0;                     // signal standard deviation of standardized y
  double log_noise = -6;                     // noise standard deviation of standardized y
};

class GaussianProcess {
 public:
  explicit GaussianProcess(int dim);

  int dim() const { return dim_; }
  size_t size() const { return y_.size(); }
  const GpHyperparameters& hyper() const { return hyper_; }
  void set_hyper(const GpHyperparameters& h);

  // Adds an observation; the factor is extended in O(n^2) with the current standardization.
  void add(const double* x, double y);
  // Re-standardizes y and maximizes the log marginal likelihood over the hyperparameters
  // (at most `max_evals` likelihood evaluations), then refactors.
  void fit(int max_evals = 60);

  // Posterior mean and variance of the latent function at x, in y units.
  void predict(const double* x, double* mean, double* variance) const;
  // The same for m points (row by row in `x`, m x dim).
  void predict(const double* x, size_t m, double* mean, double* variance) const;
  // log p(y | X, hyperparameters) of the standardized data.
  double log_marginal_likelihood() const;

 private:
  void kernel_row(const double* xs, size_t n, double* out) const;  // Matern 5/2, xs against points 0..n-1
  void rescale();                                         // xs_ = x_ / length scales
  void refactor();                                        // full Cholesky and alpha
  void solve_alpha();                                     // alpha = K^-1 (y - mean) / scale

  int dim_;
  GpHyperparameters hyper_;
  std::array<double, kMaxDim> inv_length_{};
  double signal2_ = 1, noise2_ = 1e-12;
  std::vector<double> x_, y_;  // n x dim inputs, n outputs
  // Inputs divided by the length scales (r^2 = |xs_i - xs_j|^2), one array per dimension so
  // that kernel_row's distances run over the points in vector lanes.
  std::array<std::vector<double>, kMaxDim> xs_;
  double y_mean_ = 0, y_scale_ = 1;
  Eigen::MatrixXd chol_;       // lower-triangular factor of K + noise I in its top-left n x n
  Eigen::VectorXd alpha_;
  bool factor_ok_ = true;
};

}  // namespace uvpress::bo
