// The mesh-wise stage (mesh_stage.h). How:
//
// Local step (per triangle, closed forms): for every k in 0..3, two exact block updates
//   R = polar(w_R R-bar R(k pi/2) + w_rs J S^T)              (exact minimizer of eq. 25)
//   S = (w_S S-bar + w_rs sym(R^T J)) / (w_S + w_rs)           (eq. 26, S^T = S)
// and the k with the lowest energy of eq. 19 is kept; a triangle keeps its current
// (k, R, S) unless the candidate is strictly better, so the local step never raises eq. 19.
// (The paper picks k by |J - R-bar R(k pi/2)|; with w_rs << w_R, w_S the energy picks by
// |J - R-bar R(k pi/2) S-bar|, the same idea with the stretch included.)
//
// Global step: eq. 27, sum w_rs |J_i - R_i S_i|^2 + w_b sum B(det J_i), with the barrier of
// Schueller et al. 2013: B(x) = 1/g(x/s_i) - 1, g(u) = 1 - (1-u)^3, for 0 < x < s_i, 0 for
// x >= s_i (C2), +inf for x <= 0, threshold s_i = barrier_threshold * det S-bar_i. Damped
// Newton: exact Hessian of the fit term, barrier Hessian B'' cof cof^T + |B'| P_anti (its
// indefinite part B' Hess(det) clamped to PSD), on the fixed pattern of
// solve::SparseSystem (vertex 0 pinned: the translation null space), then the maximal
// non-inverting step and Armijo backtracking (solve::max_injective_step, solve::armijo).
// The fit term's matrix depends on the input UVs only and is factorized once per chart:
// with no active barrier the Newton step is one solve with it (exact); with a few active
// barriers, PCG preconditioned by it; with more, a numeric refactorization of the full
// Hessian. After each global step, w_b /= 20 when w_rs E_rs < w_b E_barrier (eq. 28).
// The objective eq. 19 + w_b E_barrier never increases from one iteration to the next.
// With weak stretch weights and rotation targets that disagree with the neighbours', the
// formulation itself favours shrinking a triangle (|J - R S| -> 0 as J, S -> 0; the paper's
// "triangles approach degeneration"): the barrier is what keeps those from collapsing.
//
// Weights: w_R, w_S are floored at max(weight_floor, weight_floor_relative * mean weight of
// the chart); non-finite or negative weights count as 0. Nothing here becomes singular at
// w = 0 (the global matrix is w_rs times a Laplacian-like matrix plus a PSD barrier), the
// floor only keeps flat-signal triangles (w ~ 1e-16) from being pure followers. Note that
// the pull of a triangle toward its target per local-global iteration is about
// w / (w + w_rs): weights far below w_rs converge slowly (see max_iterations).
//
// Triangles whose input UV area is not positive (2A <= 1e-12 * longest edge^2, or clockwise)
// have no Jacobian: they are "passive" - no energy, no barrier, not checked for flips - and
// their vertices move with the rest. Charts should be one connected piece (only vertex 0 is
// pinned). Deterministic: per-triangle loops are OpenMP static with fixed-order sums, and
// CHOLMOD runs with BLAS on one thread (solve::configure_blas_threads).
#include "perceptual/mesh_stage.h"

#include "core/mat2.h"
#include "core/parallel.h"
#include "core/stopwatch.h"
#include "solve/line_search.h"
#include "solve/pcg.h"
#include "solve/sparse_system.h"
#include "solve/triangle_energy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

namespace uvpress::perceptual {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Per-triangle data of the local step (indices of active triangles).
struct Targets {
  std::vector<double> rotation, stretch;  // R-bar (orthonormalized), S-bar (symmetrized)
  std::vector<double> wR, wS, threshold;
};

// The active triangles of a chart: their corners and inverse input edge matrices.
struct Geometry {
  size_t vertex_count = 0;
  std::vector<uint32_t> index;  // active -> original triangle
  std::vector<uint32_t> tris;   // 3 per active triangle
  std::vector<double> rinv;     // 4 per active triangle
  size_t size() const { return index.size(); }
};

Geometry make_geometry(const std::vector<double>& uv0, const std::vector<uint32_t>& triangles) {
  Geometry g;
  g.vertex_count = uv0.size() / 2;
  const size_t nt = triangles.size() / 3;
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t* v = &triangles[3 * t];
    const double* x0 = &uv0[2 * size_t(v[0])];
    const double* x1 = &uv0[2 * size_t(v[1])];
    const double* x2 = &uv0[2 * size_t(v[2])];
    const double P[4] = {x1[0] - x0[0], x2[0] - x0[0], x1[1] - x0[1], x2[1] - x0[1]};
    const double e2 = std::max({P[0] * P[0] + P[2] * P[2], P[1] * P[1] + P[3] * P[3],
                                (P[1] - P[0]) * (P[1] - P[0]) + (P[3] - P[2]) * (P[3] - P[2])});
    const double d = det(P);
    if (!(d > 1e-12 * e2) || !std::isfinite(d)) continue;  // passive
    g.index.push_back(uint32_t(t));
    g.tris.insert(g.tris.end(), v, v + 3);
    g.rinv.insert(g.rinv.end(), {P[3] / d, -P[1] / d, -P[2] / d, P[0] / d});
  }
  return g;
}

// Eq. 27 per active triangle: fit w_rs |J - T|^2 and barrier B(det J) (unweighted).
// Returns false when the triangle is inverted or degenerate.
inline bool triangle_terms(const Geometry& g, size_t a, const double* uv, const double* T, double s, double& fit,
                           double& bar) {
  double J[4];
  jacobian(&g.rinv[4 * a], uv, &g.tris[3 * a], J);
  fit = dist2(J, T);
  bar = detail::barrier(det(J), s);
  return std::isfinite(bar);
}

// Global energy eq. 27 (active-triangle arrays T, s); +inf when a triangle is inverted.
double global_energy_active(const Geometry& g, const std::vector<double>& T, const std::vector<double>& s,
                            double w_rs, double w_b, const std::vector<double>& uv, std::vector<double>& scratch,
                            double* e_rs = nullptr, double* e_bar = nullptr) {
  const long n = long(g.size());
  scratch.resize(2 * size_t(n));
  int bad = 0;
#pragma omp parallel for schedule(static) if (worth_threads(n)) reduction(+ : bad)
  for (long a = 0; a < n; ++a) {
    double fit, bar;
    if (!triangle_terms(g, size_t(a), uv.data(), &T[4 * size_t(a)], s[size_t(a)], fit, bar)) ++bad, bar = 0;
    scratch[size_t(a)] = fit, scratch[size_t(n + a)] = bar;
  }
  if (bad) return kInf;
  const double rs = fixed_order_sum(size_t(n), scratch.data());
  const double br = fixed_order_sum(size_t(n), scratch.data() + n);
  if (e_rs) *e_rs = w_rs * rs;
  if (e_bar) *e_bar = w_b * br;
  return w_rs * rs + w_b * br;
}

// Per active triangle: gradient (6) of eq. 27, and when bar21 is given the barrier's PSD
// Hessian proxy alone (21; the fit term's 2 w_rs I is the fixed base matrix). Returns
// whether the barrier is active (det J < s).
inline bool triangle_derivatives(const Geometry& g, size_t a, const double* uv, const double* T, double s,
                                 double w_rs, double w_b, double* grad6, double* bar21) {
  double J[4];
  const double* Ri = &g.rinv[4 * a];
  jacobian(Ri, uv, &g.tris[3 * a], J);
  double d1 = 0, d2 = 0;
  detail::barrier(det(J), s, &d1, &d2);
  const bool active = d1 != 0 || d2 != 0;
  const double cof[4] = {J[3], -J[2], -J[1], J[0]};  // d det / d vec(J)
  double G[4];
  for (int k = 0; k < 4; ++k) G[k] = 2 * w_rs * (J[k] - T[k]) + w_b * d1 * cof[k];
  solve::triangle_gradient(Ri, G, 1.0, grad6);
  if (bar21 && active) {
    // w_b (B'' cof cof^T + |B'| P_anti): Hess(det) has eigenvalues +1 on the similarities
    // and -1 on the anti-similarities (P_anti projects onto them); B' < 0, so B' Hess(det)
    // is clamped to its PSD part |B'| P_anti.
    double K[16];
    const double b2 = w_b * d2, b1 = w_b * std::abs(d1) * 0.5;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) K[4 * r + c] = b2 * cof[r] * cof[c];
    K[0] += b1, K[3] -= b1, K[12] -= b1, K[15] += b1;
    K[5] += b1, K[6] += b1, K[9] += b1, K[10] += b1;
    solve::local_hessian(Ri, K, 1.0, bar21);
  }
  return active;
}

// Up to this many active barriers, PCG with the base factorization; beyond, a new
// factorization of the full Hessian (each active triangle adds up to rank 3, and CG needs
// about one iteration per rank, each costing a solve).
constexpr int kFewActive = 4;

// y6 = H6 x6 for a symmetric 6x6 stored as its row-major lower triangle (21).
inline void apply21(const double* h, const double* x, double* y) {
  for (int r = 0; r < 6; ++r) y[r] = 0;
  for (int r = 0, k = 0; r < 6; ++r)
    for (int c = 0; c <= r; ++c, ++k) {
      y[r] += h[k] * x[c];
      if (c != r) y[c] += h[k] * x[r];
    }
}

// Gradient (2 per vertex) gathered in corner order: the same bits as SparseSystem's gather.
void scatter_gradient(const Geometry& g, const std::vector<double>& grad6, std::vector<double>& grad) {
  grad.assign(2 * g.vertex_count, 0.0);
  for (size_t c = 0; c < g.tris.size(); ++c) {
    const size_t v = g.tris[c], a = c / 3, corner = c % 3;
    grad[2 * v] += grad6[6 * a + 2 * corner], grad[2 * v + 1] += grad6[6 * a + 2 * corner + 1];
  }
}

class MeshStage {
 public:
  MeshStage(const Geometry& g, const Targets& tg, const MeshStageOptions& o)
      : g_(g), tg_(tg), o_(o), system_(g.vertex_count, g.tris) {
    system_.break_factorization(o.test_break_factorization);
    const size_t n = g.size();
    k_.assign(n, 0);
    R_.assign(4 * n, 0);
    S_.assign(4 * n, 0);
    T_.assign(4 * n, 0);
    for (size_t a = 0; a < n; ++a) {
      R_[4 * a] = R_[4 * a + 3] = 1;
      for (int q = 0; q < 4; ++q) S_[4 * a + size_t(q)] = tg_.stretch[4 * a + size_t(q)];
    }
    base21_.resize(21 * n);
    const double K[16] = {2 * o.w_rs, 0, 0, 0, 0, 2 * o.w_rs, 0, 0, 0, 0, 2 * o.w_rs, 0, 0, 0, 0, 2 * o.w_rs};
    for (size_t a = 0; a < n; ++a) solve::local_hessian(&g.rinv[4 * a], K, 1.0, &base21_[21 * a]);
    e19_.resize(n);
    w_b_ = o.barrier_weight * o.w_rs;
  }

  // Local step: k, R, S per triangle at the current uv; never raises eq. 19.
  void local_step(const std::vector<double>& uv, bool initialized) {
    const long n = long(g_.size());
    const double wrs = o_.w_rs;
#pragma omp parallel for schedule(static) if (worth_threads(n))
    for (long ai = 0; ai < n; ++ai) {
      const size_t a = size_t(ai);
      double J[4];
      jacobian(&g_.rinv[4 * a], uv.data(), &g_.tris[3 * a], J);
      const double* Rb = &tg_.rotation[4 * a];
      const double* Sb = &tg_.stretch[4 * a];
      const double wR = tg_.wR[a], wS = tg_.wS[a];
      double* R = &R_[4 * a];
      double* S = &S_[4 * a];
      double best = initialized ? energy19(J, a, k_[a], R, S) : kInf;
      int best_k = k_[a];
      double best_R[4] = {R[0], R[1], R[2], R[3]}, best_S[4] = {S[0], S[1], S[2], S[3]};
      for (int k = 0; k < 4; ++k) {
        double Rt[4];
        rotated_target(Rb, k, Rt);
        double Rc[4], Sc[4] = {S[0], S[1], S[2], S[3]};
        for (int rep = 0; rep < 2; ++rep) {
          // R = polar(w_R Rt + w_rs J Sc^T)
          const double M[4] = {wR * Rt[0] + wrs * (J[0] * Sc[0] + J[1] * Sc[1]),
                               wR * Rt[1] + wrs * (J[0] * Sc[2] + J[1] * Sc[3]),
                               wR * Rt[2] + wrs * (J[2] * Sc[0] + J[3] * Sc[1]),
                               wR * Rt[3] + wrs * (J[2] * Sc[2] + J[3] * Sc[3])};
          polar(M, Rc);
          // S = (w_S S-bar + w_rs sym(R^T J)) / (w_S + w_rs)
          const double A00 = Rc[0] * J[0] + Rc[2] * J[2], A01 = Rc[0] * J[1] + Rc[2] * J[3];
          const double A10 = Rc[1] * J[0] + Rc[3] * J[2], A11 = Rc[1] * J[1] + Rc[3] * J[3];
          const double inv = 1 / (wS + wrs), off = 0.5 * (A01 + A10);
          Sc[0] = (wS * Sb[0] + wrs * A00) * inv;
          Sc[1] = Sc[2] = (wS * Sb[1] + wrs * off) * inv;
          Sc[3] = (wS * Sb[3] + wrs * A11) * inv;
        }
        const double e = energy19(J, a, k, Rc, Sc);
        if (e < best) {
          best = e, best_k = k;
          std::copy(Rc, Rc + 4, best_R);
          std::copy(Sc, Sc + 4, best_S);
        }
      }
      k_[a] = best_k;
      std::copy(best_R, best_R + 4, R);
      std::copy(best_S, best_S + 4, S);
      mul(R, S, &T_[4 * a]);
      e19_[a] = best;
    }
  }

  double energy19() const { return fixed_order_sum(e19_.size(), e19_.data()); }
  double barrier_energy(const std::vector<double>& uv) {  // w_b E_barrier
    double e_bar = 0;
    global_energy_active(g_, T_, tg_.threshold, o_.w_rs, w_b_, uv, scratch_, nullptr, &e_bar);
    return e_bar;
  }

  // Global step: damped Newton on eq. 27 for the current T = R S; then eq. 28.
  // The fit term's Hessian (2 w_rs per Jacobian entry) depends on the input UVs only: it is
  // factorized once per chart. Without an active barrier the Newton step is one solve with
  // it (exact); with active barriers, PCG on the full Hessian preconditioned by that factor
  // - the difference has rank <= 3 per active triangle, so CG needs few iterations, and
  // every CG iterate is a descent direction.
  void global_step(std::vector<double>& uv, MeshStageResult& res) {
    const long n = long(g_.size());
    Stopwatch clock;
    if (!base_ready_) {
      system_.assemble(base21_);
      base_ok_ = system_.factorize();
      base_ready_ = true;
      ++res.factorizations;
      res.t_factorization += clock.lap();
      if (!base_ok_) fail(res, "fit matrix: " + system_.failure());
    }
    if (!base_ok_) return;  // no step: the input stays (flip-free)
    grad6_.resize(6 * size_t(n));
    bar21_.resize(21 * size_t(n));
    active_.resize(size_t(n));
    auto F = [&](const std::vector<double>& x) {
      return global_energy_active(g_, T_, tg_.threshold, o_.w_rs, w_b_, x, scratch_);
    };
    const double stop = o_.tolerance;  // relative gain that ends the Newton loop
    for (int it = 0; it < o_.newton_iterations; ++it) {
      const double f0 = F(uv);
      if (!std::isfinite(f0)) break;  // cannot happen: every accepted iterate is flip-free
      int active = 0;
#pragma omp parallel for schedule(static) if (worth_threads(n)) reduction(+ : active)
      for (long a = 0; a < n; ++a) {
        const bool on = triangle_derivatives(g_, size_t(a), uv.data(), &T_[4 * size_t(a)], tg_.threshold[size_t(a)],
                                             o_.w_rs, w_b_, &grad6_[6 * size_t(a)], &bar21_[21 * size_t(a)]);
        active_[size_t(a)] = on;
        active += on;
      }
      system_.gather_gradient(grad6_, grad_);
      res.t_derivatives += clock.lap();
      if (active == 0) {
        system_.solve(grad_, dir_);
      } else if (active <= kFewActive) {
        res.cg_iterations += pcg();
      } else {  // many barriers: factorize the full Hessian (a second system; the base stays)
        if (!full_) {
          full_ = std::make_unique<solve::SparseSystem>(g_.vertex_count, g_.tris);
          // The hook counts factorizations over both systems; the base has used one.
          if (o_.test_break_factorization > 1) full_->break_factorization(o_.test_break_factorization - res.factorizations);
        }
        hess21_.resize(21 * size_t(n));
#pragma omp parallel for schedule(static) if (worth_threads(n))
        for (long a = 0; a < n; ++a)
          for (int k = 0; k < 21; ++k)
            hess21_[21 * size_t(a) + size_t(k)] =
                base21_[21 * size_t(a) + size_t(k)] + (active_[size_t(a)] ? bar21_[21 * size_t(a) + size_t(k)] : 0.0);
        full_->assemble(hess21_);
        res.t_derivatives += clock.lap();
        ++res.factorizations;
        const bool ok = full_->factorize();
        res.t_factorization += clock.lap();
        if (!ok) {
          fail(res, "full Hessian (" + std::to_string(active) + " active barriers): " + full_->failure());
          break;
        }
        full_->solve(grad_, dir_);
      }
      res.t_solve += clock.lap();
      double slope = 0;
      for (size_t i = 0; i < dir_.size(); ++i) slope += grad_[i] * dir_[i];
      // Newton decrement: stop when the quadratic model promises (almost) nothing.
      if (!(slope < 0) || -0.5 * slope <= stop * f0) {
        res.t_line_search += clock.lap();
        break;
      }
      const double a_max = solve::max_injective_step(g_.tris, uv, dir_);
      const double a0 = std::min(1.0, 0.9 * a_max);
      const auto ls = solve::armijo(uv, dir_, f0, slope, a0, F);
      ++res.newton_steps;
      const bool exact = active == 0 && ls.step == 1 && barrier_energy(uv) == 0;  // minimizer of the quadratic
      res.t_line_search += clock.lap();
      if (ls.step == 0 || exact || f0 - ls.energy <= stop * f0) break;
    }
    // Eq. 28 at the new uv.
    double e_rs = 0, e_bar = 0;
    global_energy_active(g_, T_, tg_.threshold, o_.w_rs, w_b_, uv, scratch_, &e_rs, &e_bar);
    if (e_rs < e_bar) w_b_ /= o_.barrier_shrink;
    res.t_line_search += clock.lap();
  }

  double w_b() const { return w_b_; }
  bool base_failed() const { return base_ready_ && !base_ok_; }
  const std::vector<int>& k() const { return k_; }

 private:
  // y = H x with H = base + active barriers, rows and columns of the pinned dofs 0, 1 zero.
  void apply_hessian(const std::vector<double>& x, std::vector<double>& y) {
    const long n = long(g_.size());
    y6_.resize(6 * size_t(n));
#pragma omp parallel for schedule(static) if (worth_threads(n))
    for (long ai = 0; ai < n; ++ai) {
      const size_t a = size_t(ai);
      const uint32_t* v = &g_.tris[3 * a];
      const double x6[6] = {x[2 * size_t(v[0])], x[2 * size_t(v[0]) + 1], x[2 * size_t(v[1])],
                            x[2 * size_t(v[1]) + 1], x[2 * size_t(v[2])], x[2 * size_t(v[2]) + 1]};
      double* y6 = &y6_[6 * a];
      apply21(&base21_[21 * a], x6, y6);
      if (active_[a]) {
        double b6[6];
        apply21(&bar21_[21 * a], x6, b6);
        for (int k = 0; k < 6; ++k) y6[k] += b6[k];
      }
    }
    system_.gather_gradient(y6_, y);
    y[0] = y[1] = 0;
  }

  // H dir = -grad by conjugate gradients preconditioned with the base factorization,
  // from dir = 0 (solve/pcg.h). Inexact Newton: the preconditioned residual norm down by
  // 1e-2 is enough. Returns the iterations.
  int pcg() {
    constexpr int kMaxIterations = 20;
    constexpr double kRelative = 1e-2;
    const size_t m = grad_.size();
    rhs_.assign(m, 0.0);
    for (size_t i = 2; i < m; ++i) rhs_[i] = -grad_[i];
    // The base factor pins vertex 0 (sparse_system.h): M^-1 r = solve(-r).
    const auto res = solve::pcg([this](const std::vector<double>& x, std::vector<double>& y) { apply_hessian(x, y); },
                                [this](const std::vector<double>& r, std::vector<double>& z) {
                                  neg_r_.resize(r.size());
                                  for (size_t i = 0; i < r.size(); ++i) neg_r_[i] = -r[i];
                                  system_.solve(neg_r_, z);
                                },
                                rhs_, dir_, kRelative, kMaxIterations, pcg_work_);
    return res.iterations;
  }

  // The first failure is the one reported.
  static void fail(MeshStageResult& res, const std::string& why) {
    if (res.failed()) return;
    res.status = MeshStageStatus::FactorizationFailed;
    res.failure = why;
  }

  static void rotated_target(const double* Rb, int k, double* Rt) {
    static const double quarter[4][4] = {{1, 0, 0, 1}, {0, -1, 1, 0}, {-1, 0, 0, -1}, {0, 1, -1, 0}};
    mul(Rb, quarter[k], Rt);
  }
  double energy19(const double* J, size_t a, int k, const double* R, const double* S) const {
    double Rt[4], RS[4];
    rotated_target(&tg_.rotation[4 * a], k, Rt);
    mul(R, S, RS);
    return tg_.wR[a] * dist2(R, Rt) + tg_.wS[a] * dist2(S, &tg_.stretch[4 * a]) + o_.w_rs * dist2(J, RS);
  }

  const Geometry& g_;
  const Targets& tg_;
  const MeshStageOptions& o_;
  solve::SparseSystem system_;
  std::vector<int> k_;
  std::vector<double> R_, S_, T_, e19_;
  std::unique_ptr<solve::SparseSystem> full_;
  std::vector<double> base21_, bar21_, hess21_, grad6_, grad_, dir_, scratch_, y6_;
  std::vector<double> rhs_, neg_r_;  // PCG: -grad pinned, and -r for the base solve
  solve::PcgWork pcg_work_;
  std::vector<char> active_;
  double w_b_ = 0;
  bool base_ready_ = false, base_ok_ = false;
};

}  // namespace

const char* to_string(MeshStageStatus s) {
  switch (s) {
    case MeshStageStatus::Optimized: return "optimized";
    case MeshStageStatus::NoActiveTriangles: return "no active triangles";
    case MeshStageStatus::FactorizationFailed: return "factorization failed";
  }
  return "?";
}

namespace detail {

double barrier(double x, double s, double* d1, double* d2) {
  if (d1) *d1 = 0;
  if (d2) *d2 = 0;
  if (!(x > 0)) return kInf;
  if (x >= s) return 0;
  // B = 1/g - 1, g(x) = 1 - (1 - x/s)^3: g' = 3 (1-u)^2 / s, g'' = -6 (1-u) / s^2.
  const double u = x / s, m = 1 - u;
  const double g = 1 - m * m * m, g1 = 3 * m * m / s, g2 = -6 * m / (s * s);
  if (d1) *d1 = -g1 / (g * g);
  if (d2) *d2 = 2 * g1 * g1 / (g * g * g) - g2 / (g * g);
  return 1 / g - 1;
}

double global_energy(const std::vector<double>& uv0, const std::vector<uint32_t>& triangles,
                     const std::vector<double>& T, const std::vector<double>& s, double w_rs, double w_b,
                     const std::vector<double>& uv, std::vector<double>* gradient) {
  const Geometry g = make_geometry(uv0, triangles);
  std::vector<double> Ta(4 * g.size()), sa(g.size()), scratch;
  for (size_t a = 0; a < g.size(); ++a) {
    std::copy(&T[4 * size_t(g.index[a])], &T[4 * size_t(g.index[a])] + 4, &Ta[4 * a]);
    sa[a] = s[g.index[a]];
  }
  const double e = global_energy_active(g, Ta, sa, w_rs, w_b, uv, scratch);
  if (gradient) {
    std::vector<double> grad6(6 * g.size());
    for (size_t a = 0; a < g.size(); ++a)
      triangle_derivatives(g, a, uv.data(), &Ta[4 * a], sa[a], w_rs, w_b, &grad6[6 * a], nullptr);
    scatter_gradient(g, grad6, *gradient);
  }
  return e;
}

}  // namespace detail

MeshStageResult fit_chart(const std::vector<double>& uv, const std::vector<uint32_t>& triangles,
                          const std::vector<TriangleTarget>& targets, const MeshStageOptions& o) {
  if (uv.size() % 2 || triangles.size() % 3 || targets.size() != triangles.size() / 3)
    throw std::invalid_argument("fit_chart: expected 2 UVs per vertex, 3 indices and 1 target per triangle");
  const size_t nv = uv.size() / 2, nt = triangles.size() / 3;
  for (uint32_t v : triangles)
    if (v >= nv) throw std::invalid_argument("fit_chart: triangle index out of range");
  if (!(o.w_rs > 0) || !(o.barrier_weight > 0) || !(o.barrier_threshold > 0) || !(o.barrier_shrink >= 1) ||
      o.max_iterations < 0 || o.newton_iterations < 1 || !(o.tolerance >= 0))
    throw std::invalid_argument("fit_chart: options out of range");

  MeshStageResult res;
  res.uv = uv;
  res.k.assign(nt, 0);
  res.jacobian.assign(4 * nt, 0.0);
  const Geometry g = make_geometry(uv, triangles);
  res.passive = nt - g.size();
  if (g.size() == 0) {
    res.status = MeshStageStatus::NoActiveTriangles;
    return res;
  }

  // Targets of the active triangles: R-bar orthonormalized, S-bar symmetrized, weights floored.
  Targets tg;
  const size_t n = g.size();
  tg.rotation.resize(4 * n), tg.stretch.resize(4 * n), tg.wR.resize(n), tg.wS.resize(n), tg.threshold.resize(n);
  auto clean = [](double w) { return std::isfinite(w) && w > 0 ? w : 0.0; };
  double mean = 0;
  for (size_t a = 0; a < n; ++a) {
    const TriangleTarget& t = targets[g.index[a]];
    polar(t.rotation.data(), &tg.rotation[4 * a]);
    const double off = 0.5 * (t.stretch[1] + t.stretch[2]);
    double* S = &tg.stretch[4 * a];
    S[0] = t.stretch[0], S[1] = S[2] = off, S[3] = t.stretch[3];
    tg.wR[a] = clean(t.weight_rotation), tg.wS[a] = clean(t.weight_stretch);
    mean += 0.5 * (tg.wR[a] + tg.wS[a]);
    const double d = det(S);
    tg.threshold[a] = o.barrier_threshold * (std::isfinite(d) ? std::max(d, 1e-6) : 1.0);
  }
  mean /= double(n);
  const double floor = std::max(o.weight_floor, o.weight_floor_relative * mean);
  for (size_t a = 0; a < n; ++a) tg.wR[a] = std::max(tg.wR[a], floor), tg.wS[a] = std::max(tg.wS[a], floor);

  MeshStage stage(g, tg, o);
  std::vector<double>& x = res.uv;
  stage.local_step(x, false);
  double e19 = stage.energy19();
  double objective = e19 + stage.barrier_energy(x);
  res.objective_history.push_back(objective);
  res.energy_history.push_back(e19);
  for (int it = 1; it <= o.max_iterations; ++it) {
    stage.global_step(x, res);
    if (stage.base_failed()) {  // no global step is possible: the input stays, untouched
      x = uv;
      break;
    }
    Stopwatch clock;
    stage.local_step(x, true);
    res.t_local += clock.lap();
    e19 = stage.energy19();
    const double next = e19 + stage.barrier_energy(x);
    res.objective_history.push_back(next);
    res.energy_history.push_back(e19);
    res.iterations = it;
    const bool converged = !(objective - next > o.tolerance * objective);
    objective = next;
    if (converged) break;
  }
  res.energy = e19;
  res.barrier_weight = stage.w_b();
  for (size_t a = 0; a < n; ++a) {
    const size_t t = g.index[a];
    res.k[t] = stage.k()[a];
    double J[4];
    jacobian(&g.rinv[4 * a], x.data(), &g.tris[3 * a], J);
    std::copy(J, J + 4, &res.jacobian[4 * t]);
    if (!(det(J) > 0)) ++res.flips;
  }
  return res;
}

}  // namespace uvpress::perceptual
