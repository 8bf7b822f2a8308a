// GP-BO against known optima (Branin, Hartmann-4) and against random search.
#include <catch2/catch.hpp>

#include "bo/bayes_opt.h"

#include <cmath>
#include <functional>
#include <random>

using namespace uvpress::bo;

namespace {

// Branin on [-5, 10] x [0, 15]; global minimum 0.397887 (three places).
double branin(const double* u) {
  double x = -5 + 15 * u[0], y = 15 * u[1];
  double a = y - 5.1 / (4 * M_PI * M_PI) * x * x + 5 / M_PI * x - 6;
  return a * a + 10 * (1 - 1 / (8 * M_PI)) * std::cos(x) + 10;
}

// Hartmann on [0,1]^4 with the first four columns of the 6-D constants (unscaled);
// minimum -3.72984 near (0.1873, 0.1941, 0.5578, 0.2649), found by multistart local search.
double hartmann4(const double* x) {
  static const double alpha[4] = {1.0, 1.2, 3.0, 3.2};
  static const double A[4][4] = {{10, 3, 17, 3.5}, {0.05, 10, 17, 0.1}, {3, 3.5, 1.7, 10}, {17, 8, 0.05, 10}};
  static const double P[4][4] = {
      {0.1312, 0.1696, 0.5569, 0.0124}, {0.2329, 0.4135, 0.8307, 0.3736},
      {0.2348, 0.1451, 0.3522, 0.2883}, {0.4047, 0.8828, 0.8732, 0.5743}};
  double s = 0;
  for (int i = 0; i < 4; ++i) {
    double e = 0;
    for (int j = 0; j < 4; ++j) e += A[i][j] * (x[j] - P[i][j]) * (x[j] - P[i][j]);
    s += alpha[i] * std::exp(-e);
  }
  return -s;
}

double run_bo(int dim, const std::function<double(const double*)>& f, int budget, uint64_t seed) {
  BoOptions o;
  o.dim = dim, o.seed = seed;
  BayesOpt bo(o);
  double best = INFINITY;
  double x[kMaxDim];
  for (int k = 0; k < budget; ++k) {
    bo.propose([&](const double*, double m, double sd) { return expected_improvement(best, m, sd); }, x);
    double y = f(x);
    best = std::min(best, y);
    bo.observe(x, y);
  }
  return best;
}

double run_random(int dim, const std::function<double(const double*)>& f, int budget, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  double best = INFINITY, x[kMaxDim];
  for (int k = 0; k < budget; ++k) {
    for (int d = 0; d < dim; ++d) x[d] = u(rng);
    best = std::min(best, f(x));
  }
  return best;
}

}  // namespace

TEST_CASE("GP-BO finds Branin's minimum within 0.02 in 60 evaluations", "[bo]") {
  CHECK(run_bo(2, branin, 60, 1) < 0.397887 + 0.02);
}

TEST_CASE("GP-BO finds Hartmann-4's minimum within 0.1 in 100 evaluations", "[bo]") {
  CHECK(run_bo(4, hartmann4, 100, 1) < -3.72984 + 0.1);
}

TEST_CASE("GP-BO beats random search with the same budget, averaged over 10 seeds", "[bo]") {
  double bo_b = 0, rs_b = 0, bo_h = 0, rs_h = 0;
  for (uint64_t seed = 1; seed <= 10; ++seed) {
    bo_b += run_bo(2, branin, 30, seed), rs_b += run_random(2, branin, 30, seed);
    bo_h += run_bo(4, hartmann4, 60, seed), rs_h += run_random(4, hartmann4, 60, seed);
  }
  INFO("Branin: BO " << bo_b / 10 << " random " << rs_b / 10 << "; Hartmann-4: BO " << bo_h / 10 << " random "
                      << rs_h / 10);
  CHECK(bo_b < rs_b);
  CHECK(bo_h < rs_h);
  CHECK(bo_b / 10 < 0.6);    // random search: about 2.1
  CHECK(bo_h / 10 < -3.4);   // random search: about -3.0
}

TEST_CASE("Halton points fill the box evenly", "[bo]") {
  // 64 points in an 8 x 8 grid: uniform random points leave about 23 cells empty.
  int cells[8][8] = {};
  double p[2];
  for (int k = 1; k <= 64; ++k) {
    halton(uint64_t(k), 2, nullptr, p);
    cells[int(p[0] * 8)][int(p[1] * 8)]++;
  }
  int empty = 0;
  for (auto& row : cells)
    for (int c : row) empty += c == 0;
  CHECK(empty <= 12);
}
