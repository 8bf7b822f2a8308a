// Preconditioned conjugate gradients for an SPD system A x = b, from x = 0: every iterate
// is then a descent direction of the quadratic model, so a Newton-type caller may stop
// early (inexact Newton) and still step downhill. Dots and updates run in index order on
// one thread, so the iterates' bits do not depend on the thread count.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

namespace uvpress::solve {

enum class PcgStop {
  Converged,    // the preconditioned residual norm fell by `tolerance`
  Budget,       // max_iterations spent first
  NotPositive,  // p^T A p <= 0 or not finite: A is not SPD (or the data are not finite)
};

struct PcgResult {
  PcgStop stop = PcgStop::Converged;
  int iterations = 0;
};

// Work vectors kept between calls (no allocation per solve).
struct PcgWork {
  std::vector<double> r, z, p, q;
};

// x = A^-1 b approximately: apply(p, q) sets q = A p; precondition(r, z) sets z = M^-1 r.
// Stops when r^T M^-1 r <= tolerance^2 r0^T M^-1 r0, after max_iterations, or when A
// shows a direction of non-positive curvature; x is the last iterate in every case.
template <class Apply, class Precondition>
PcgResult pcg(Apply&& apply, Precondition&& precondition, const std::vector<double>& b, std::vector<double>& x,
              double tolerance, int max_iterations, PcgWork& w) {
  const size_t n = b.size();
  auto dot = [n](const std::vector<double>& u, const std::vector<double>& v) {
    double s = 0;
    for (size_t i = 0; i < n; ++i) s += u[i] * v[i];
    return s;
  };
  w.r = b;
  x.assign(n, 0.0);
  precondition(w.r, w.z);
  w.p = w.z;
  double rz = dot(w.r, w.z);
  const double stop = tolerance * tolerance * rz;
  PcgResult res;
  while (rz > stop) {
    if (res.iterations == max_iterations) return res.stop = PcgStop::Budget, res;
    apply(w.p, w.q);
    const double pq = dot(w.p, w.q);
    if (!(pq > 0)) return res.stop = PcgStop::NotPositive, res;
    const double alpha = rz / pq;
    for (size_t i = 0; i < n; ++i) x[i] += alpha * w.p[i], w.r[i] -= alpha * w.q[i];
    ++res.iterations;
    precondition(w.r, w.z);
    const double rz_next = dot(w.r, w.z);
    const double beta = rz_next / rz;
    rz = rz_next;
    for (size_t i = 0; i < n; ++i) w.p[i] = w.z[i] + beta * w.p[i];
  }
  if (!std::isfinite(rz)) res.stop = PcgStop::NotPositive;
  return res;
}

}  // namespace uvpress::solve
