// Mesh-wise stage (perceptual-loss paper §4.2, Appendix B): local-global fit of per-triangle
// targets R-bar S-bar up to 90-degree rotations, flip-free.
#include "perceptual/mesh_stage.h"

#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <functional>
#include <random>

using namespace uvpress::perceptual;

namespace {

struct Chart {
  std::vector<double> uv;
  std::vector<uint32_t> tris;
  size_t triangle_count() const { return tris.size() / 3; }
};

// n x n squares of `h` texels, two CCW triangles each; interior vertices jittered by
// `jitter` * h (deterministic).
Chart grid(int n, double h = 2.0, double jitter = 0.0, uint32_t seed = 7) {
  Chart c;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const bool interior = i > 0 && j > 0 && i < n && j < n;
      const double dx = interior ? jitter * h * u(rng) : 0, dy = interior ? jitter * h * u(rng) : 0;
      c.uv.push_back(10 + i * h + dx);
      c.uv.push_back(20 + j * h + dy);
    }
  auto id = [n](int i, int j) { return uint32_t(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      c.tris.insert(c.tris.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      c.tris.insert(c.tris.end(), {id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return c;
}

double centroid_u(const Chart& c, const std::vector<double>& uv, size_t t) {
  return (uv[2 * c.tris[3 * t]] + uv[2 * c.tris[3 * t + 1]] + uv[2 * c.tris[3 * t + 2]]) / 3;
}

std::array<double, 4> rot(double a) { return {std::cos(a), -std::sin(a), std::sin(a), std::cos(a)}; }

TriangleTarget target(const std::array<double, 4>& R, const std::array<double, 4>& S, double w = 1) {
  TriangleTarget t;
  t.rotation = R, t.stretch = S, t.weight_rotation = w, t.weight_stretch = w;
  return t;
}

// max |x_i - (s A x0_i + b)| over vertices, with b fitting the centroids (A = s I).
double deviation_from_scaled(const std::vector<double>& x, const std::vector<double>& x0, double s) {
  const size_t nv = x.size() / 2;
  double c[2] = {0, 0}, c0[2] = {0, 0};
  for (size_t v = 0; v < nv; ++v)
    for (int r = 0; r < 2; ++r) c[r] += x[2 * v + r] / double(nv), c0[r] += x0[2 * v + r] / double(nv);
  double worst = 0;
  for (size_t v = 0; v < nv; ++v)
    for (int r = 0; r < 2; ++r) worst = std::max(worst, std::abs((x[2 * v + r] - c[r]) - s * (x0[2 * v + r] - c0[r])));
  return worst;
}

double jdet(const MeshStageResult& r, size_t t) {
  const double* J = &r.jacobian[4 * t];
  return J[0] * J[3] - J[1] * J[2];
}

double jdist(const MeshStageResult& r, size_t t, const std::array<double, 4>& T) {
  double s = 0;
  for (int q = 0; q < 4; ++q) s += (r.jacobian[4 * t + size_t(q)] - T[size_t(q)]) * (r.jacobian[4 * t + size_t(q)] - T[size_t(q)]);
  return std::sqrt(s);
}

void check_monotone(const MeshStageResult& r) {
  for (size_t i = 1; i < r.objective_history.size(); ++i) {
    INFO("iteration " << i << ": " << r.objective_history[i - 1] << " -> " << r.objective_history[i]);
    CHECK(r.objective_history[i] <= r.objective_history[i - 1] * (1 + 1e-12) + 1e-300);
  }
}

const std::array<double, 4> I2{1, 0, 0, 1};

}  // namespace

TEST_CASE("mesh stage: identity targets keep the input", "[perceptual][mesh]") {
  const Chart c = grid(12, 3.0, 0.3);
  std::vector<TriangleTarget> targets(c.triangle_count(), target(I2, I2));
  const auto r = fit_chart(c.uv, c.tris, targets, {});
  CHECK(r.flips == 0);
  CHECK(r.passive == 0);
  CHECK(r.energy < 1e-20);
  CHECK(deviation_from_scaled(r.uv, c.uv, 1.0) < 1e-9);
  for (int k : r.k) CHECK(k == 0);
}

TEST_CASE("mesh stage: a uniform scale is met exactly", "[perceptual][mesh]") {
  const Chart c = grid(20, 2.0, 0.25);
  std::vector<TriangleTarget> targets(c.triangle_count(), target(I2, {0.5, 0, 0, 0.5}));
  const auto r = fit_chart(c.uv, c.tris, targets, {});
  CHECK(r.flips == 0);
  CHECK(deviation_from_scaled(r.uv, c.uv, 0.5) < 1e-6);
  CHECK(deviation_from_scaled(c.uv, c.uv, 0.5) > 5);  // the check can fail
  CHECK(r.energy < 1e-15);
  check_monotone(r);
  // An anisotropic target: the same stretch everywhere is an affine map.
  std::vector<TriangleTarget> aniso(c.triangle_count(), target(I2, {0.8, 0.1, 0.1, 0.3}));
  const auto a = fit_chart(c.uv, c.tris, aniso, {});
  for (size_t t = 0; t < c.triangle_count(); ++t) CHECK(jdist(a, t, {0.8, 0.1, 0.1, 0.3}) < 1e-6);
}

TEST_CASE("mesh stage: 90-degree rotations are absorbed by k, other rotations are not", "[perceptual][mesh]") {
  const Chart c = grid(10, 2.0, 0.3);
  const double q = std::acos(-1.0) / 2;
  for (int quarter = 1; quarter <= 3; ++quarter) {
    std::vector<TriangleTarget> targets(c.triangle_count(), target(rot(quarter * q), {0.5, 0, 0, 0.5}));
    const auto r = fit_chart(c.uv, c.tris, targets, {});
    CHECK(r.flips == 0);
    CHECK(r.energy < 1e-15);
    for (int k : r.k) CHECK(k == 4 - quarter);  // R-bar R(k pi/2) = I
    // Scaled, not rotated.
    CHECK(deviation_from_scaled(r.uv, c.uv, 0.5) < 1e-6);
  }
  // A 30-degree rotation is honoured: nearest quarter is k = 0, the chart turns.
  std::vector<TriangleTarget> targets(c.triangle_count(), target(rot(q / 3), I2));
  const auto r = fit_chart(c.uv, c.tris, targets, {});
  for (int k : r.k) CHECK(k == 0);
  for (size_t t = 0; t < c.triangle_count(); ++t) CHECK(jdist(r, t, rot(q / 3)) < 1e-6);
  // Mixed quarters per triangle (R-bar = R(k_t pi/2) R(10 deg)): all consistent up to k.
  std::vector<TriangleTarget> mixed;
  for (size_t t = 0; t < c.triangle_count(); ++t) mixed.push_back(target(rot(double(t % 4) * q + q / 9), I2));
  const auto m = fit_chart(c.uv, c.tris, mixed, {});
  CHECK(m.energy < 1e-12);
  for (size_t t = 0; t < c.triangle_count(); ++t) {
    CHECK(m.k[t] == int((4 - t % 4) % 4));
    CHECK(jdist(m, t, rot(q / 9)) < 1e-6);
  }
}

TEST_CASE("mesh stage: inconsistent targets stay flip-free and move toward their areas", "[perceptual][mesh]") {
  const Chart c = grid(30, 2.0, 0.2);
  std::vector<TriangleTarget> targets;
  const double mid = 10 + 30;
  for (size_t t = 0; t < c.triangle_count(); ++t)
    targets.push_back(target(I2, centroid_u(c, c.uv, t) < mid ? std::array<double, 4>{0.2, 0, 0, 0.2} : I2));
  const auto r = fit_chart(c.uv, c.tris, targets, {});
  CHECK(r.flips == 0);
  CHECK(r.iterations >= 1);
  REQUIRE(r.objective_history.size() == size_t(r.iterations) + 1);
  check_monotone(r);
  CHECK(r.objective_history.back() < 0.5 * r.objective_history.front());
  double left = 0, right = 0, min_det = 1e300;
  size_t nl = 0, nr = 0;
  for (size_t t = 0; t < c.triangle_count(); ++t) {
    const double d = jdet(r, t);
    min_det = std::min(min_det, d);
    if (centroid_u(c, c.uv, t) < mid) left += d, ++nl;
    else right += d, ++nr;
  }
  left /= double(nl), right /= double(nr);
  INFO("mean area ratio left " << left << " right " << right << " min " << min_det);
  CHECK(min_det > 0);
  CHECK(left < 0.25);   // from 1 toward 0.04
  CHECK(right > 0.5);   // stays near 1
  CHECK(left < 0.3 * right);
}

TEST_CASE("mesh stage: the weights decide who gives way", "[perceptual][mesh]") {
  const Chart c = grid(20, 2.0, 0.2);
  const double mid = 10 + 20;
  const std::array<double, 4> small{0.3, 0, 0, 0.3};
  auto run = [&](double w_left, double w_right, double& err_left, double& err_right) {
    std::vector<TriangleTarget> targets;
    for (size_t t = 0; t < c.triangle_count(); ++t)
      targets.push_back(centroid_u(c, c.uv, t) < mid ? target(I2, small, w_left) : target(I2, I2, w_right));
    const auto r = fit_chart(c.uv, c.tris, targets, {});
    CHECK(r.flips == 0);
    check_monotone(r);
    err_left = err_right = 0;
    size_t nl = 0, nr = 0;
    for (size_t t = 0; t < c.triangle_count(); ++t)
      if (centroid_u(c, c.uv, t) < mid) err_left += jdist(r, t, small), ++nl;
      else err_right += jdist(r, t, I2), ++nr;
    err_left /= double(nl), err_right /= double(nr);
  };
  // Weights on the scale of GMSD variances, around w_rs = 1e-5.
  double al, ar, bl, br;
  run(1e-3, 1e-8, al, ar);
  run(1e-8, 1e-3, bl, br);
  INFO("heavy left: " << al << " " << ar << "; heavy right: " << bl << " " << br);
  CHECK(al < 0.5 * ar);
  CHECK(br < 0.5 * bl);
  CHECK(al < 0.5 * bl);
  CHECK(br < 0.5 * ar);
}

TEST_CASE("mesh stage: random targets never flip a triangle", "[perceptual][mesh]") {
  const Chart c = grid(16, 2.0, 0.3, 11);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(0, 6.283185307179586), lambda(0.05, 1), logw(-9, -3);
  std::vector<TriangleTarget> targets;
  for (size_t t = 0; t < c.triangle_count(); ++t) {
    const double b = angle(rng), l1 = lambda(rng), l2 = lambda(rng);
    const double cb = std::cos(b), sb = std::sin(b);
    TriangleTarget x = target(rot(angle(rng)), {l1 * cb * cb + l2 * sb * sb, (l1 - l2) * cb * sb,
                                                (l1 - l2) * cb * sb, l1 * sb * sb + l2 * cb * cb});
    x.weight_rotation = std::pow(10.0, logw(rng)), x.weight_stretch = std::pow(10.0, logw(rng));
    targets.push_back(x);
  }
  targets[5].weight_rotation = targets[5].weight_stretch = 0;  // flat signal
  targets[9].weight_stretch = 1e-16;
  const auto r = fit_chart(c.uv, c.tris, targets, {});
  CHECK(r.flips == 0);
  for (size_t t = 0; t < c.triangle_count(); ++t) CHECK(jdet(r, t) > 0);
  for (double x : r.uv) CHECK(std::isfinite(x));
  check_monotone(r);
  CHECK(r.objective_history.back() < r.objective_history.front());
  // Deterministic: the same bits twice.
  const auto again = fit_chart(c.uv, c.tris, targets, {});
  CHECK(again.uv == r.uv);
  CHECK(again.k == r.k);
}

TEST_CASE("mesh stage: degenerate input triangles are passive, bad input throws", "[perceptual][mesh]") {
  Chart c = grid(6, 2.0, 0.0);
  // Collapse one triangle's UVs onto a segment by adding a degenerate triangle (a sliver
  // with three collinear corners) that shares vertices with the chart.
  c.tris.insert(c.tris.end(), {0, 1, 2});
  std::vector<TriangleTarget> targets(c.triangle_count(), target(I2, {0.5, 0, 0, 0.5}));
  const auto r = fit_chart(c.uv, c.tris, targets, {});
  CHECK(r.passive == 1);
  CHECK(r.flips == 0);
  CHECK(deviation_from_scaled(r.uv, c.uv, 0.5) < 1e-6);
  for (double x : r.uv) CHECK(std::isfinite(x));

  CHECK_THROWS_AS(fit_chart(c.uv, c.tris, {}, {}), std::invalid_argument);
  std::vector<uint32_t> bad = c.tris;
  bad[0] = 1000;
  CHECK_THROWS_AS(fit_chart(c.uv, bad, targets, {}), std::invalid_argument);
  MeshStageOptions o;
  o.w_rs = 0;
  CHECK_THROWS_AS(fit_chart(c.uv, c.tris, targets, o), std::invalid_argument);
}

TEST_CASE("mesh stage: a failed factorization is the chart's status, the input kept", "[perceptual][mesh]") {
  const Chart c = grid(10, 2.0, 0.2);
  std::vector<TriangleTarget> targets(c.triangle_count(), target(I2, {0.5, 0, 0, 0.5}));
  const auto ok = fit_chart(c.uv, c.tris, targets, {});
  CHECK(ok.status == MeshStageStatus::Optimized);
  CHECK_FALSE(ok.failed());
  CHECK(ok.failure.empty());
  CHECK(deviation_from_scaled(ok.uv, c.uv, 0.5) < 1e-6);

  // The fit term's matrix (the first factorization) fails: nothing moves, and it says so.
  MeshStageOptions o;
  o.test_break_factorization = 1;
  const auto r = fit_chart(c.uv, c.tris, targets, o);
  CHECK(r.status == MeshStageStatus::FactorizationFailed);
  CHECK(r.failed());
  CHECK(std::string(to_string(r.status)) == "factorization failed");
  CHECK_THAT(r.failure, Catch::Contains("fit matrix") && Catch::Contains("not positive definite"));
  CHECK(r.uv == c.uv);
  CHECK(r.iterations == 0);
  CHECK(r.factorizations == 1);
  CHECK(r.flips == 0);
}

TEST_CASE("mesh stage: a failed full-Hessian factorization is reported, the iterate stays flip-free",
          "[perceptual][mesh]") {
  // Random rotation targets with weak weights: triangles shrink onto their barriers, and
  // with many barriers active the full Hessian is factorized.
  const Chart c = grid(16, 2.0, 0.3, 11);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(0, 6.283185307179586), lambda(0.05, 1), logw(-9, -3);
  std::vector<TriangleTarget> targets;
  for (size_t t = 0; t < c.triangle_count(); ++t) {
    const double b = angle(rng), l1 = lambda(rng), l2 = lambda(rng);
    const double cb = std::cos(b), sb = std::sin(b);
    TriangleTarget x = target(rot(angle(rng)), {l1 * cb * cb + l2 * sb * sb, (l1 - l2) * cb * sb,
                                                (l1 - l2) * cb * sb, l1 * sb * sb + l2 * cb * cb});
    x.weight_rotation = std::pow(10.0, logw(rng)), x.weight_stretch = std::pow(10.0, logw(rng));
    targets.push_back(x);
  }
  const auto ok = fit_chart(c.uv, c.tris, targets, {});
  INFO(ok.factorizations << " factorizations, " << ok.cg_iterations << " CG iterations");
  REQUIRE(ok.factorizations >= 2);
  CHECK(ok.status == MeshStageStatus::Optimized);
  MeshStageOptions o;
  o.test_break_factorization = 2;
  const auto r = fit_chart(c.uv, c.tris, targets, o);
  CHECK(r.status == MeshStageStatus::FactorizationFailed);
  CHECK_THAT(r.failure, Catch::Contains("full Hessian") && Catch::Contains("not positive definite"));
  CHECK(r.flips == 0);
  for (double x : r.uv) CHECK(std::isfinite(x));
}

TEST_CASE("mesh stage: a chart with no usable triangle says so", "[perceptual][mesh]") {
  const std::vector<double> uv{0, 0, 1, 0, 2, 0};  // collinear: passive
  const auto r = fit_chart(uv, {0, 1, 2}, {target(I2, I2)}, {});
  CHECK(r.status == MeshStageStatus::NoActiveTriangles);
  CHECK_FALSE(r.failed());
  CHECK(r.uv == uv);
}

TEST_CASE("mesh stage: barrier and global energy derivatives match finite differences", "[perceptual][mesh]") {
  // Barrier: C2 at the threshold, +inf at 0.
  for (double x : {0.01, 0.05, 0.1, 0.19}) {
    double d1, d2;
    detail::barrier(x, 0.2, &d1, &d2);
    const double h = 1e-6 * x;
    const double fd1 = (detail::barrier(x + h, 0.2) - detail::barrier(x - h, 0.2)) / (2 * h);
    double a1, b1;
    detail::barrier(x + h, 0.2, &a1), detail::barrier(x - h, 0.2, &b1);
    CHECK(d1 == Approx(fd1).epsilon(1e-6));
    CHECK(d2 == Approx((a1 - b1) / (2 * h)).epsilon(1e-5));
    CHECK(d1 < 0);
    CHECK(d2 > 0);
  }
  CHECK(detail::barrier(0.2, 0.2) == 0);
  CHECK(detail::barrier(0.2 - 1e-9, 0.2) < 1e-20);
  CHECK(std::isinf(detail::barrier(0, 0.2)));
  CHECK(std::isinf(detail::barrier(-1, 0.2)));

  const Chart c = grid(5, 1.5, 0.3);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::vector<double> x = c.uv;
  for (double& v : x) v += u(rng);
  std::vector<double> T, s;
  for (size_t t = 0; t < c.triangle_count(); ++t) {
    T.insert(T.end(), {0.6 + u(rng), u(rng), u(rng), 0.6 + u(rng)});
    s.push_back(t % 2 ? 2.0 : 0.05);  // half the triangles inside the barrier
  }
  const double w_rs = 1e-5, w_b = 3e-4;
  std::vector<double> g;
  const double e = detail::global_energy(c.uv, c.tris, T, s, w_rs, w_b, x, &g);
  REQUIRE(std::isfinite(e));
  REQUIRE(g.size() == x.size());
  double gmax = 0;
  for (double v : g) gmax = std::max(gmax, std::abs(v));
  for (size_t i = 0; i < x.size(); ++i) {
    const double h = 1e-6;
    std::vector<double> p = x, m = x;
    p[i] += h, m[i] -= h;
    const double fd = (detail::global_energy(c.uv, c.tris, T, s, w_rs, w_b, p) -
                       detail::global_energy(c.uv, c.tris, T, s, w_rs, w_b, m)) / (2 * h);
    CHECK(std::abs(g[i] - fd) < 1e-6 * gmax);
  }
  // Translation invariance: the gradient sums to zero.
  double su = 0, sv = 0;
  for (size_t v = 0; v < x.size() / 2; ++v) su += g[2 * v], sv += g[2 * v + 1];
  CHECK(std::abs(su) < 1e-12 * gmax * double(x.size()));
  CHECK(std::abs(sv) < 1e-12 * gmax * double(x.size()));
}

// Timing on a ~10K-triangle synthetic chart (hidden: run with "[mesh-bench]").
TEST_CASE("mesh stage: 10K-triangle synthetic chart", "[.][perceptual][mesh-bench]") {
  const Chart c = grid(71, 2.0, 0.25);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> angle(-0.3, 0.3), logw(-8, -4);
  std::vector<TriangleTarget> targets;
  for (size_t t = 0; t < c.triangle_count(); ++t) {
    const double x = (centroid_u(c, c.uv, t) - 10) / 142;
    const double l = 0.2 + 0.8 * (0.5 + 0.5 * std::sin(6 * x));
    TriangleTarget tt = target(rot(angle(rng) + (t % 3 == 0 ? 1.5707963267948966 : 0)), {l, 0, 0, 0.7 * l});
    tt.weight_rotation = std::pow(10.0, logw(rng)), tt.weight_stretch = std::pow(10.0, logw(rng));
    targets.push_back(tt);
  }
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = fit_chart(c.uv, c.tris, targets, {});
  const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  WARN("triangles " << c.triangle_count() << " iterations " << r.iterations << " newton " << r.newton_steps
                    << " factorizations " << r.factorizations << " cg " << r.cg_iterations << " seconds " << sec << " energy "
                    << r.objective_history.front() << " -> " << r.energy << " flips " << r.flips << " local "
                    << r.t_local << " derivatives " << r.t_derivatives << " factorization " << r.t_factorization
                    << " solve " << r.t_solve << " line search " << r.t_line_search);
  for (size_t i = 0; i < r.objective_history.size(); i += 10) WARN(i << ": " << r.objective_history[i]);
  CHECK(r.flips == 0);
  check_monotone(r);
}
