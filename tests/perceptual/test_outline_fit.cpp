#include <catch2/catch.hpp>

#include "perceptual/outline_fit.h"

#include <cmath>
#include <vector>

using namespace uvpress;

namespace {

// An n x n grid of squares (two triangles each, counter-clockwise in x-right / y-down
// terms as reparam's charts are: positive signed area), side `size` texels.
void grid(int n, double size, std::vector<double>& uv, std::vector<uint32_t>& tris) {
  uv.clear(), tris.clear();
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) uv.push_back(size * i / n), uv.push_back(size * j / n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t a = uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n) + 2, d = a + uint32_t(n) + 1;
      tris.insert(tris.end(), {a, b, c, a, c, d});
    }
}

double area(const double* a, const double* b, const double* c) {
  return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
}

double total_area(const std::vector<double>& uv, const std::vector<uint32_t>& t) {
  double A = 0;
  for (size_t k = 0; k < t.size(); k += 3) A += area(&uv[2 * t[k]], &uv[2 * t[k + 1]], &uv[2 * t[k + 2]]);
  return A;
}

// sum_t A0_t |J_t(u) - J_t(target)|^2, Jacobians relative to uv0.
double misfit(const std::vector<double>& uv0, const std::vector<double>& u, const std::vector<double>& target,
              const std::vector<uint32_t>& t) {
  double e = 0;
  for (size_t k = 0; k < t.size(); k += 3) {
    const double* p[3] = {&uv0[2 * t[k]], &uv0[2 * t[k + 1]], &uv0[2 * t[k + 2]]};
    const double E[4] = {p[1][0] - p[0][0], p[2][0] - p[0][0], p[1][1] - p[0][1], p[2][1] - p[0][1]};
    const double d = E[0] * E[3] - E[1] * E[2];
    const double Ei[4] = {E[3] / d, -E[1] / d, -E[2] / d, E[0] / d};
    auto jac = [&](const std::vector<double>& v, double J[4]) {
      const double F[4] = {v[2 * t[k + 1]] - v[2 * t[k]], v[2 * t[k + 2]] - v[2 * t[k]], v[2 * t[k + 1] + 1] - v[2 * t[k] + 1],
                           v[2 * t[k + 2] + 1] - v[2 * t[k] + 1]};
      J[0] = F[0] * Ei[0] + F[1] * Ei[2], J[1] = F[0] * Ei[1] + F[1] * Ei[3];
      J[2] = F[2] * Ei[0] + F[3] * Ei[2], J[3] = F[2] * Ei[1] + F[3] * Ei[3];
    };
    double a[4], b[4];
    jac(u, a), jac(target, b);
    double s = 0;
    for (int i = 0; i < 4; ++i) s += (a[i] - b[i]) * (a[i] - b[i]);
    e += 0.5 * std::abs(d) * s;
  }
  return e;
}

}  // namespace

TEST_CASE("outline fit: a bulged result goes back into the input's square, interior redistributed", "[perceptual]") {
  std::vector<double> uv0;
  std::vector<uint32_t> tris;
  grid(10, 100, uv0, tris);
  // The "mesh stage result": the right half grows (x stretched 1.8x there), the left half
  // shrinks (0.6x), and the sides bulge (x also scaled with y): the outline is no square.
  std::vector<double> uv1 = uv0;
  for (size_t v = 0; v < uv1.size() / 2; ++v) {
    const double x = uv0[2 * v], y = uv0[2 * v + 1];
    const double xs = x < 50 ? 0.6 * x : 30 + 1.8 * (x - 50);
    uv1[2 * v] = xs * (1 + 0.2 * std::sin(M_PI * y / 100));
    uv1[2 * v + 1] = y;
  }
  const auto fit = perceptual::keep_outline(uv0, uv1, tris);
  REQUIRE(fit.ok());
  CHECK(fit.blend == 0);
  const double s = std::sqrt(total_area(uv1, tris) / total_area(uv0, tris));
  CHECK(total_area(fit.uv, tris) == Approx(s * s * 100 * 100).epsilon(1e-9));  // the outline's area
  // Every boundary vertex on the scaled square (centred where the input's vertex mean was),
  // the corners at its corners.
  double lo[2] = {1e9, 1e9}, hi[2] = {-1e9, -1e9};
  for (size_t v = 0; v < fit.uv.size() / 2; ++v)
    for (int k = 0; k < 2; ++k) lo[k] = std::min(lo[k], fit.uv[2 * v + k]), hi[k] = std::max(hi[k], fit.uv[2 * v + k]);
  CHECK(hi[0] - lo[0] == Approx(100 * s));
  CHECK(hi[1] - lo[1] == Approx(100 * s));
  for (size_t v = 0; v < fit.uv.size() / 2; ++v) {
    const bool boundary = uv0[2 * v] == 0 || uv0[2 * v] == 100 || uv0[2 * v + 1] == 0 || uv0[2 * v + 1] == 100;
    if (!boundary) continue;
    const double x = fit.uv[2 * v], y = fit.uv[2 * v + 1];
    const double to_side = std::min({std::abs(x - lo[0]), std::abs(x - hi[0]), std::abs(y - lo[1]), std::abs(y - hi[1])});
    CHECK(to_side < 1e-9);
  }
  // No triangle folds, and the interior follows the result: the left half narrower than the
  // right at mid-height, and closer to the result's Jacobians than the input scaled.
  for (size_t k = 0; k < tris.size(); k += 3) CHECK(area(&fit.uv[2 * tris[k]], &fit.uv[2 * tris[k + 1]], &fit.uv[2 * tris[k + 2]]) > 0);
  const size_t mid = 5 * 11 + 5;  // vertex (5, 5): x = 50 in the input
  CHECK(fit.uv[2 * mid] - lo[0] < 0.4 * (hi[0] - lo[0]));
  std::vector<double> scaled(uv0.size());
  for (size_t k = 0; k < uv0.size(); ++k) scaled[k] = s * uv0[k];
  CHECK(misfit(uv0, fit.uv, uv1, tris) < 0.5 * misfit(uv0, scaled, uv1, tris));
}

TEST_CASE("outline fit: a result that would fold is blended toward the uniform scale", "[perceptual]") {
  std::vector<double> uv0;
  std::vector<uint32_t> tris;
  grid(6, 60, uv0, tris);
  // One interior vertex pushed far across its neighbours: the result's Jacobians there
  // cannot be matched inside the square without folding.
  std::vector<double> uv1 = uv0;
  const size_t v = 3 * 7 + 3;
  uv1[2 * v] += 200;
  uv1[2 * v + 1] += 150;
  const auto fit = perceptual::keep_outline(uv0, uv1, tris);
  REQUIRE(fit.ok());
  for (size_t k = 0; k < tris.size(); k += 3) CHECK(area(&fit.uv[2 * tris[k]], &fit.uv[2 * tris[k + 1]], &fit.uv[2 * tris[k + 2]]) > 0);
  INFO("blend " << fit.blend);
  CHECK(fit.blend > 0);
  // A chart whose boundary is not closed loops (a pinch: two squares sharing one corner)
  // is refused, not guessed.
  std::vector<double> two = {0, 0, 1, 0, 1, 1, 0, 1, 2, 1, 2, 2, 1, 2};
  std::vector<uint32_t> t2 = {0, 1, 2, 0, 2, 3, 2, 4, 5, 2, 5, 6};
  CHECK_FALSE(perceptual::keep_outline(two, two, t2).ok());
}
