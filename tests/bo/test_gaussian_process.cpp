#include <catch2/catch.hpp>

#include "bo/gaussian_process.h"

#include <Eigen/Dense>

#include <cmath>

using namespace uvpress::bo;

namespace {

double matern52(const double* a, const double* b, const double* length, double signal2) {
  double r2 = 0;
  for (int d = 0; d < 2; ++d) r2 += (a[d] - b[d]) * (a[d] - b[d]) / (length[d] * length[d]);
  double r = std::sqrt(5 * r2);
  return signal2 * (1 + r + r * r / 3) * std::exp(-r);
}

}  // namespace

TEST_CASE("GP posterior mean and variance equal the closed form", "[bo]") {
  const double X[4][2] = {{0.1, 0.2}, {0.8, 0.3}, {0.4, 0.9}, {0.5, 0.5}};
  const double y[4] = {1.0, -0.5, 2.0, 0.3};
  const double length[2] = {0.3, 0.5}, signal = 1.2, noise = 1e-3;
  GaussianProcess gp(2);
  GpHyperparameters h;
  h.log_length[0] = std::log(length[0]), h.log_length[1] = std::log(length[1]);
  h.log_signal = std::log(signal), h.log_noise = std::log(noise);
  gp.set_hyper(h);
  for (int i = 0; i < 4; ++i) gp.add(X[i], y[i]);

  // Constant prior mean: the first observation, until the first fit (see gaussian_process.h).
  Eigen::Matrix4d K;
  Eigen::Vector4d r;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) K(i, j) = matern52(X[i], X[j], length, signal * signal);
    K(i, i) += noise * noise;
    r(i) = y[i] - y[0];
  }
  for (auto q : {std::array<double, 2>{0.3, 0.3}, {0.9, 0.9}, {0.5, 0.5}}) {
    Eigen::Vector4d k;
    for (int i = 0; i < 4; ++i) k(i) = matern52(q.data(), X[i], length, signal * signal);
    double mean_ref = y[0] + k.dot(K.ldlt().solve(r));
    double var_ref = signal * signal - k.dot(K.ldlt().solve(k));
    double mean, var;
    gp.predict(q.data(), &mean, &var);
    CHECK(mean == Approx(mean_ref).epsilon(1e-7));
    CHECK(var == Approx(var_ref).epsilon(1e-5).margin(1e-9));
  }
}

TEST_CASE("GP interpolates its data and fitting raises the marginal likelihood", "[bo]") {
  GaussianProcess gp(2);
  std::vector<std::array<double, 2>> pts;
  for (int i = 0; i < 25; ++i) pts.push_back({(i % 5 + 0.5) / 5, (i / 5 + 0.5) / 5});
  auto f = [](const std::array<double, 2>& p) { return std::sin(6 * p[0]) + 0.3 * p[1] * p[1]; };
  for (auto& p : pts) gp.add(p.data(), f(p));
  gp.fit(200);
  const double fitted = gp.log_marginal_likelihood();
  GpHyperparameters fitted_h = gp.hyper();
  gp.set_hyper(GpHyperparameters{{std::log(0.3), std::log(0.3)}, 0, -6});
  CHECK(fitted >= gp.log_marginal_likelihood());
  gp.set_hyper(fitted_h);
  for (auto& p : pts) {
    double m, v;
    gp.predict(p.data(), &m, &v);
    CHECK(m == Approx(f(p)).margin(0.02));
  }
  double m, v;
  const double off[2] = {0.42, 0.61};
  gp.predict(off, &m, &v);
  CHECK(m == Approx(f({0.42, 0.61})).margin(0.05));  // smooth function: good between samples
}
