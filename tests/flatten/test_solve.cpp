// host/solve: the two-thread split factorization (split_cholesky.h) and its float
// preconditioner against CHOLMOD's double solve of the whole matrix, the same bits
// whatever the thread count, and failures reported.
#include <catch2/catch.hpp>

#include "solve/sparse_system.h"
#include "solve/split_cholesky.h"

#include <cmath>
#include <cstring>
#include <omp.h>
#include <vector>

using namespace uvpress::solve;

namespace {

double hash01(uint32_t x) {
  uint32_t h = x * 0x8da6b343u;
  h ^= h >> 13, h *= 0x5bd1e995u, h ^= h >> 15;
  return (h & 0xffffff) / double(0x1000000);
}

// The shape of flatten's systems: an n x n grid's vertices, u and v coupled. Every edge
// (a, b) adds (e_a - e_b)(e_a - e_b)' (x) M_e, M_e a 2x2 SPD matrix with anisotropy up to
// 1:20 (the SLIM and CM proxies' weights), plus 1e-6 on the diagonal: SPD, and as badly
// conditioned as a 2-D Laplacian of that size. Lower triangle, column-major.
Eigen::SparseMatrix<double> grid_system(int n) {
  const int nv = (n + 1) * (n + 1);
  std::vector<Eigen::Triplet<double>> t;
  auto edge = [&](int a, int b, uint32_t id) {
    const double s1 = 1 + 19 * hash01(3 * id), s2 = 1 + hash01(3 * id + 1), angle = 6.283 * hash01(3 * id + 2);
    const double c = std::cos(angle), s = std::sin(angle);
    const double M[2][2] = {{s1 * c * c + s2 * s * s, (s1 - s2) * c * s}, {(s1 - s2) * c * s, s1 * s * s + s2 * c * c}};
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) {
        t.emplace_back(2 * a + i, 2 * a + j, M[i][j]);
        t.emplace_back(2 * b + i, 2 * b + j, M[i][j]);
        t.emplace_back(2 * a + i, 2 * b + j, -M[i][j]);
        t.emplace_back(2 * b + i, 2 * a + j, -M[i][j]);
      }
  };
  uint32_t id = 0;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const int v = j * (n + 1) + i;
      if (i < n) edge(v, v + 1, id++);
      if (j < n) edge(v, v + n + 1, id++);
      if (i < n && j < n) edge(v, v + n + 2, id++);
    }
  for (int k = 0; k < 2 * nv; ++k) t.emplace_back(k, k, 1e-6);
  Eigen::SparseMatrix<double> full(2 * nv, 2 * nv);
  full.setFromTriplets(t.begin(), t.end());
  Eigen::SparseMatrix<double> lower = full.triangularView<Eigen::Lower>();
  lower.makeCompressed();
  return lower;
}

double relative_error(const std::vector<double>& z, const Eigen::VectorXd& x) {
  double err = 0, norm = 0;
  for (size_t i = 0; i < z.size(); ++i) err += (z[i] - x[long(i)]) * (z[i] - x[long(i)]), norm += x[long(i)] * x[long(i)];
  return std::sqrt(err / norm);
}

struct Factored {
  Eigen::SparseMatrix<double> A;
  SupernodalLLT llt;
  explicit Factored(int n) : A(grid_system(n)) {
    const SerialCholmod serial;
    llt.compute(A);
    REQUIRE(llt.info() == Eigen::Success);
  }
};

std::vector<double> wave(size_t n, double k) {
  std::vector<double> r(n);
  for (size_t i = 0; i < n; ++i) r[i] = std::sin(k * double(i)) + 0.1 * hash01(uint32_t(i));
  return r;
}

}  // namespace

// The split factorization is exact (double, up to round-off): its solve is CHOLMOD's solve
// of the whole matrix within 1e-10, its float preconditioner within float rounding.
TEST_CASE("solve: the split factorization solves like CHOLMOD on the whole matrix", "[flatten][solve]") {
  Factored whole(180);  // 32,761 vertices, 65,522 dofs
  const size_t n = size_t(whole.A.rows());
  SplitCholesky split;
  REQUIRE(split.analyze(whole.A));
  INFO("separator " << split.separator() << " of " << n << " dofs");
  CHECK(split.separator() > 0);
  CHECK(split.separator() < int(0.05 * double(n)));
  REQUIRE(split.factorize(whole.A, 0.0));
  CHECK(split.failure().empty());
  for (double k : {0.001, 0.37}) {
    const std::vector<double> r = wave(n, k);
    const Eigen::VectorXd x = whole.llt.solve(Eigen::Map<const Eigen::VectorXd>(r.data(), long(n)));
    std::vector<double> direct(n), preconditioned(n);
    split.solve(r.data(), direct.data());
    split.precondition(r.data(), preconditioned.data());
    INFO("k " << k << ": direct " << relative_error(direct, x) << ", float " << relative_error(preconditioned, x));
    CHECK(relative_error(direct, x) < 1e-10);
    CHECK(relative_error(preconditioned, x) < 1e-5);
    CHECK(relative_error(preconditioned, x) > 1e-9);  // the float copies, not the double factors
  }
  // A new factorization of other values in the same pattern (what every Newton step does).
  Eigen::SparseMatrix<double> B = whole.A;
  for (int col = 0; col < B.outerSize(); ++col) B.valuePtr()[B.outerIndexPtr()[col]] *= 1.5;  // diagonals
  SupernodalLLT llt;
  llt.compute(B);
  REQUIRE(split.factorize(B, 0.0));
  const std::vector<double> r = wave(n, 0.05);
  std::vector<double> direct(n);
  split.solve(r.data(), direct.data());
  CHECK(relative_error(direct, llt.solve(Eigen::Map<const Eigen::VectorXd>(r.data(), long(n)))) < 1e-10);
}

TEST_CASE("solve: the split factorization has the same bits with 1 and 2 threads", "[flatten][solve]") {
  const Eigen::SparseMatrix<double> A = grid_system(180);
  const std::vector<double> r = wave(size_t(A.rows()), 0.01);
  std::vector<double> direct[2], preconditioned[2];
  const int threads = omp_get_max_threads();
  for (int t = 0; t < 2; ++t) {
    omp_set_num_threads(t + 1);
    SplitCholesky split;
    REQUIRE(split.analyze(A));
    REQUIRE(split.factorize(A, 1e-12));
    direct[t].resize(r.size()), preconditioned[t].resize(r.size());
    split.solve(r.data(), direct[t].data());
    split.precondition(r.data(), preconditioned[t].data());
  }
  omp_set_num_threads(threads);
  CHECK(std::memcmp(direct[0].data(), direct[1].data(), r.size() * sizeof(double)) == 0);
  CHECK(std::memcmp(preconditioned[0].data(), preconditioned[1].data(), r.size() * sizeof(double)) == 0);
}

TEST_CASE("solve: the split factorization reports a matrix that is not positive definite", "[flatten][solve]") {
  Eigen::SparseMatrix<double> A = grid_system(180);
  SplitCholesky split;
  REQUIRE(split.analyze(A));
  for (long k = 0; k < A.nonZeros(); ++k) A.valuePtr()[k] = -A.valuePtr()[k];
  CHECK_FALSE(split.factorize(A, 0.0));
  CHECK_THAT(split.failure(), Catch::Contains("not positive definite"));
}

TEST_CASE("solve: a small system is not split", "[flatten][solve]") {
  SplitCholesky split;
  CHECK_FALSE(split.analyze(grid_system(6)));  // the separator is most of it
}
