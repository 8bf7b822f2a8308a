#include "perceptual/outline_fit.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace uvpress::perceptual {

namespace {

double signed_area(const double* a, const double* b, const double* c) {
  return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
}

// Gradients of the three barycentric functions of triangle (a, b, c) (signed area A != 0):
// grad phi_a = (y_b - y_c, x_c - x_b) / 2A and cyclically.
void gradients(const double* a, const double* b, const double* c, double A, double g[3][2]) {
  const double* v[3] = {a, b, c};
  for (int k = 0; k < 3; ++k) {
    const double* p = v[(k + 1) % 3];
    const double* q = v[(k + 2) % 3];
    g[k][0] = (p[1] - q[1]) / (2 * A);
    g[k][1] = (q[0] - p[0]) / (2 * A);
  }
}

// The boundary loops of a triangle set: directed edges whose reverse no triangle has, chained
// head to tail. Empty when a vertex starts two boundary edges (a pinch): no outline to keep.
std::vector<std::vector<uint32_t>> boundary_loops(const std::vector<uint32_t>& triangles, size_t n, bool& ok) {
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (size_t t = 0; t + 2 < triangles.size(); t += 3)
    for (int k = 0; k < 3; ++k) ++edges[{triangles[t + size_t(k)], triangles[t + size_t(k + 1) % 3]}];
  std::vector<uint32_t> next(n, UINT32_MAX);
  ok = true;
  for (const auto& [e, count] : edges) {
    if (edges.count({e.second, e.first})) continue;
    if (next[e.first] != UINT32_MAX || count > 1) ok = false;
    next[e.first] = e.second;
  }
  std::vector<std::vector<uint32_t>> loops;
  if (!ok) return loops;
  std::vector<char> seen(n, 0);
  for (uint32_t v = 0; v < n; ++v) {
    if (next[v] == UINT32_MAX || seen[v]) continue;
    std::vector<uint32_t> loop;
    for (uint32_t w = v; !seen[w]; w = next[w]) {
      if (next[w] == UINT32_MAX) {  // an open chain: not a closed outline
        ok = false;
        return {};
      }
      seen[w] = 1;
      loop.push_back(w);
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

// Point at arc length `s` along polyline `P` (2 per point).
void along(const std::vector<double>& P, double s, double* out) {
  const size_t m = P.size() / 2;
  for (size_t k = 0; k + 1 < m; ++k) {
    const double dx = P[2 * k + 2] - P[2 * k], dy = P[2 * k + 3] - P[2 * k + 1];
    const double len = std::hypot(dx, dy);
    if (s <= len || k + 2 == m) {
      const double f = len > 0 ? std::clamp(s / len, 0.0, 1.0) : 0.0;
      out[0] = P[2 * k] + f * dx, out[1] = P[2 * k + 1] + f * dy;
      return;
    }
    s -= len;
  }
  out[0] = P[0], out[1] = P[1];
}

}  // namespace

OutlineFit keep_outline(const std::vector<double>& uv0, const std::vector<double>& uv1,
                        const std::vector<uint32_t>& triangles, const OutlineOptions& options) {
  OutlineFit out;
  out.uv = uv1;
  const size_t n = uv0.size() / 2, nt = triangles.size() / 3;
  if (uv1.size() != uv0.size() || n == 0 || nt == 0) {
    out.failure = "sizes do not match";
    return out;
  }
  // Areas, and the result's Jacobians relative to the input (J = E1 E0^-1).
  std::vector<double> area0(nt, 0), J(4 * nt, 0);
  double A0 = 0, A1 = 0;
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t* v = &triangles[3 * t];
    if (v[0] >= n || v[1] >= n || v[2] >= n) {
      out.failure = "triangle index out of range";
      return out;
    }
    const double* a = &uv0[2 * v[0]];
    const double* b = &uv0[2 * v[1]];
    const double* c = &uv0[2 * v[2]];
    area0[t] = signed_area(a, b, c);
    A0 += std::max(0.0, area0[t]);
    A1 += std::max(0.0, signed_area(&uv1[2 * v[0]], &uv1[2 * v[1]], &uv1[2 * v[2]]));
    if (!(area0[t] > 0)) continue;
    double g[3][2];
    gradients(a, b, c, area0[t], g);
    for (int r = 0; r < 2; ++r)
      for (int k = 0; k < 3; ++k) {
        J[4 * t + 2 * size_t(r)] += uv1[2 * v[k] + size_t(r)] * g[k][0];
        J[4 * t + 2 * size_t(r) + 1] += uv1[2 * v[k] + size_t(r)] * g[k][1];
      }
  }
  if (!(A0 > 0) || !(A1 > 0)) {
    out.failure = "no positive area";
    return out;
  }
  bool ok = true;
  const auto loops = boundary_loops(triangles, n, ok);
  if (!ok || loops.empty()) {
    out.failure = "the boundary is not a set of closed loops";
    return out;
  }
  // The result's overall rotation R (Procrustes: the rotation closest to sum q p^T over
  // centred vertices) is taken out of its Jacobians: the outline keeps its input orientation.
  double c0[2] = {0, 0}, c1[2] = {0, 0};
  for (size_t v = 0; v < n; ++v) c0[0] += uv0[2 * v], c0[1] += uv0[2 * v + 1], c1[0] += uv1[2 * v], c1[1] += uv1[2 * v + 1];
  c0[0] /= double(n), c0[1] /= double(n), c1[0] /= double(n), c1[1] /= double(n);
  double M[4] = {0, 0, 0, 0};  // sum (q - c1)(p - c0)^T
  for (size_t v = 0; v < n; ++v) {
    const double p[2] = {uv0[2 * v] - c0[0], uv0[2 * v + 1] - c0[1]};
    const double q[2] = {uv1[2 * v] - c1[0], uv1[2 * v + 1] - c1[1]};
    M[0] += q[0] * p[0], M[1] += q[0] * p[1], M[2] += q[1] * p[0], M[3] += q[1] * p[1];
  }
  double cs = M[0] + M[3], sn = M[2] - M[1];
  const double norm = std::hypot(cs, sn);
  cs = norm > 0 ? cs / norm : 1.0, sn = norm > 0 ? sn / norm : 0.0;  // R = [cs -sn; sn cs]
  for (size_t t = 0; t < nt; ++t) {  // J <- R^T J
    double* j = &J[4 * t];
    const double r0 = cs * j[0] + sn * j[2], r1 = cs * j[1] + sn * j[3];
    const double r2 = -sn * j[0] + cs * j[2], r3 = -sn * j[1] + cs * j[3];
    j[0] = r0, j[1] = r1, j[2] = r2, j[3] = r3;
  }
  std::vector<double> q(2 * n);  // the result, rotation taken out
  for (size_t v = 0; v < n; ++v) {
    const double x = uv1[2 * v] - c1[0], y = uv1[2 * v + 1] - c1[1];
    q[2 * v] = cs * x + sn * y, q[2 * v + 1] = -sn * x + cs * y;
  }
  const double s = std::sqrt(A1 / A0);

  // Boundary positions: corners at the scaled input, the rest slid along the input's sides.
  std::vector<double> fixed(2 * n, 0);
  std::vector<char> on_boundary(n, 0);
  const double cos_corner = std::cos(options.corner_degrees * M_PI / 180);
  for (const auto& loop : loops) {
    const size_t m = loop.size();
    std::vector<size_t> corners;
    double sharpest = 2;
    size_t sharpest_at = 0;
    for (size_t i = 0; i < m; ++i) {
      const double* a = &uv0[2 * loop[(i + m - 1) % m]];
      const double* b = &uv0[2 * loop[i]];
      const double* c = &uv0[2 * loop[(i + 1) % m]];
      const double ux = b[0] - a[0], uy = b[1] - a[1], wx = c[0] - b[0], wy = c[1] - b[1];
      const double lu = std::hypot(ux, uy), lw = std::hypot(wx, wy);
      const double cosine = lu > 0 && lw > 0 ? (ux * wx + uy * wy) / (lu * lw) : 1.0;
      if (cosine < cos_corner) corners.push_back(i);
      if (cosine < sharpest) sharpest = cosine, sharpest_at = i;
    }
    if (corners.empty()) corners.push_back(sharpest_at);
    for (size_t k = 0; k < corners.size(); ++k) {
      const size_t from = corners[k], to = corners[(k + 1) % corners.size()];
      const size_t len = (to + m - from) % m == 0 ? m : (to + m - from) % m;  // vertices from..to, to exclusive
      std::vector<double> P, F;  // the input side (scaled), the result's arc-length fractions
      double total_q = 0;
      F.push_back(0);
      for (size_t i = 0; i <= len; ++i) {
        const uint32_t v = loop[(from + i) % m];
        P.push_back(s * (uv0[2 * v] - c0[0]));
        P.push_back(s * (uv0[2 * v + 1] - c0[1]));
        if (i > 0) {
          const uint32_t u = loop[(from + i - 1) % m];
          total_q += std::hypot(q[2 * v] - q[2 * u], q[2 * v + 1] - q[2 * u + 1]);
          F.push_back(total_q);
        }
      }
      double total_p = 0;
      for (size_t i = 0; i + 1 <= len; ++i) total_p += std::hypot(P[2 * i + 2] - P[2 * i], P[2 * i + 3] - P[2 * i + 1]);
      for (size_t i = 0; i < len; ++i) {
        const uint32_t v = loop[(from + i) % m];
        const double f = total_q > 0 ? F[i] / total_q : double(i) / double(len);
        along(P, f * total_p, &fixed[2 * v]);
        on_boundary[v] = 1;
      }
    }
  }

  // Interior: the Poisson problem over the unknown vertices, boundary eliminated.
  std::vector<int> unknown(n, -1);
  int nu = 0;
  for (size_t v = 0; v < n; ++v)
    if (!on_boundary[v]) unknown[v] = nu++;
  for (double blend : {0.0, 0.5, 1.0}) {
    std::vector<Eigen::Triplet<double>> entries;
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(std::max(nu, 1), 2);
    for (size_t t = 0; t < nt; ++t) {
      if (!(area0[t] > 0)) continue;
      const uint32_t* v = &triangles[3 * t];
      double g[3][2];
      gradients(&uv0[2 * v[0]], &uv0[2 * v[1]], &uv0[2 * v[2]], area0[t], g);
      // Target Jacobian: the result's, blended toward the uniform scale s I.
      const double T[4] = {(1 - blend) * J[4 * t] + blend * s, (1 - blend) * J[4 * t + 1],
                           (1 - blend) * J[4 * t + 2], (1 - blend) * J[4 * t + 3] + blend * s};
      for (int a = 0; a < 3; ++a) {
        const int ia = unknown[v[a]];
        if (ia < 0) continue;
        for (int r = 0; r < 2; ++r) rhs(ia, r) += area0[t] * (g[a][0] * T[2 * r] + g[a][1] * T[2 * r + 1]);
        for (int b = 0; b < 3; ++b) {
          const double k = area0[t] * (g[a][0] * g[b][0] + g[a][1] * g[b][1]);
          const int ib = unknown[v[b]];
          if (ib >= 0)
            entries.emplace_back(ia, ib, k);
          else
            for (int r = 0; r < 2; ++r) rhs(ia, r) -= k * fixed[2 * v[b] + size_t(r)];
        }
      }
    }
    std::vector<double> uv = fixed;
    if (nu > 0) {
      Eigen::SparseMatrix<double> K(nu, nu);
      K.setFromTriplets(entries.begin(), entries.end());
      Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(K);
      if (solver.info() != Eigen::Success) {
        out.failure = "the interior system is singular (vertices held only by degenerate triangles)";
        return out;
      }
      const Eigen::MatrixXd x = solver.solve(rhs);
      for (size_t v = 0; v < n; ++v)
        if (unknown[v] >= 0) uv[2 * v] = x(unknown[v], 0), uv[2 * v + 1] = x(unknown[v], 1);
    }
    bool folded = false;
    for (size_t t = 0; t < nt && !folded; ++t) {
      if (!(area0[t] > 0)) continue;
      const uint32_t* v = &triangles[3 * t];
      folded = !(signed_area(&uv[2 * v[0]], &uv[2 * v[1]], &uv[2 * v[2]]) > 0);
    }
    if (folded) continue;
    out.uv = std::move(uv);
    out.blend = blend;
    return out;
  }
  out.failure = "every blend folds a triangle";
  return out;
}

}  // namespace uvpress::perceptual
