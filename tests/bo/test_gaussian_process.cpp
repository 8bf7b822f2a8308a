#include <catch2/catch.hpp>

#include "bo/exp_neg.h"
#include "bo/gaussian_process.h"

#include <Eigen/Dense>

#include <cmath>
#include <random>

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

TEST_CASE("exp_neg is within 1 ulp of libm's exp over the kernel's whole range", "[bo]") {
  // Every exponent of 2 from 2^-30 to 708, densely, plus random points; relative to libm's
  // exp (correctly rounded in all but rare cases), counted in units of the last place.
  std::vector<double> r = {0.0, 1e-300, 0.5 * M_LN2, M_LN2, 1.0, 700.0, 708.0};
  for (double x = 0x1p-30; x < 708; x *= 1.001) r.push_back(x);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> any(0, 708);
  for (int k = 0; k < 200000; ++k) r.push_back(any(rng));
  double worst = 0, at = 0;
  for (double v : r) {
    const double want = std::exp(-v), got = exp_neg(v);
    const double ulps = std::abs(got - want) / (std::nextafter(want, INFINITY) - want);
    if (ulps > worst) worst = ulps, at = v;
  }
  INFO("worst " << worst << " ulp at r = " << at);
  CHECK(worst <= 1.0);
  CHECK(exp_neg(0.0) == 1.0);
  CHECK(exp_neg(709.0) == 0.0);   // below 2^-1021: 0 by contract
  CHECK(exp_neg(1e308) == 0.0);
}
