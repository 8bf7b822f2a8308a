#include "perceptual/triangle_stage.h"

#include "bo/bayes_opt.h"
#include "core/stopwatch.h"

#include <algorithm>
#include <cmath>
#include <future>
#include <limits>
#include <memory>
#include <stdexcept>

namespace uvpress::perceptual {

namespace {

constexpr double kHalfPi = 1.5707963267948966;
constexpr double kGmsdFloor = 1e-5;  // z = log(GMSD + floor): finite at GMSD = 0

// 12-point Gauss-Hermite rule (physicists'), for E[f(z)], z ~ N(mu, sd^2).
constexpr double kHermiteNodes[12] = {-3.889724897869782, -3.020637025120890, -2.279507080501060,
                                      -1.597682635152605, -0.9477883912401637, -0.3142403762543591,
                                      0.3142403762543591,  0.9477883912401637,  1.597682635152605,
                                      2.279507080501060,   3.020637025120890,   3.889724897869782};
constexpr double kHermiteWeights[12] = {2.658551684356302e-07, 8.573687043587859e-05, 0.003905390584629062,
                                        0.05160798561588393,   0.2604923102641611,    0.5701352362624795,
                                        0.5701352362624795,    0.2604923102641611,    0.05160798561588393,
                                        0.003905390584629062,  8.573687043587859e-05, 2.658551684356302e-07};

// The stop rule of TriangleStageOptions::early_stop: at least kStallMinimum evaluations, then
// kStallWindow without a 0.1 % gain. Chosen by replaying whole 100-evaluation searches (a
// stopped search is the whole one cut short) against the target area it costs, and checked
// on the written assets: DEVELOPERS.md, "The triangle stage's stop rule".
constexpr int kStallMinimum = 40, kStallWindow = 30;

double barrier(double g, double eps) { return g < eps ? -std::log(eps - g) : std::numeric_limits<double>::infinity(); }

// One triangle's optimization state.
struct Search {
  uint32_t triangle = 0;
  uint32_t first_view = 0, views = 1;  // its views in the wave's view set
  double area = 0;  // |T| in texels
  double eps = 0;   // its GMSD bound (eq. 12): options.epsilon, or its own under rate control
  std::unique_ptr<bo::BayesOpt> bo;
  double x[4] = {0, 0, 0, 0};  // pending proposal
  double best_f = std::numeric_limits<double>::infinity(), best_g = 0;
  double best_x[4] = {0, 1, 1, 0};
  double identity_g = -1;   // measured at the first evaluation (the identity)
  float identity_lattice = 1;
  int last_improvement = 0;
  bool done = false;
};

double objective(const Search& s, const double x[4], double g, const TriangleStageOptions& o) {
  double l1, l2;
  jacobian_of(x, o.lambda_min, nullptr, &l1, &l2);
  return l1 * l2 * s.area + barrier(g, s.eps);
}

// Expected improvement of the composite objective under z ~ N(mean, sd^2).
double acquisition(const Search& s, const double* x, double mean, double sd, const TriangleStageOptions& o) {
  const double log_eps = std::log(s.eps + kGmsdFloor);
  if (!std::isfinite(s.best_f)) return bo::normal_cdf((log_eps - mean) / std::max(sd, 1e-12));
  double l1, l2;
  jacobian_of(x, o.lambda_min, nullptr, &l1, &l2);
  const double area = l1 * l2 * s.area;
  if (area - std::log(s.eps) >= s.best_f) return 0;  // cannot improve even at GMSD = 0
  double ei = 0;
  for (int k = 0; k < 12; ++k) {
    double z = mean + sd * std::sqrt(2.0) * kHermiteNodes[k];
    double g = std::exp(z) - kGmsdFloor;
    double f = area + barrier(std::max(g, 0.0), s.eps);
    if (f < s.best_f) ei += kHermiteWeights[k] * (s.best_f - f);
  }
  return ei / std::sqrt(M_PI);
}

// `lattice`: the largest tile spacing over the triangle's views at this evaluation.
void record(Search& s, const double x[4], double g, float lattice, int evaluation, const TriangleStageOptions& o) {
  if (evaluation == 1) s.identity_g = g, s.identity_lattice = lattice;  // the first point is the identity
  s.bo->observe(x, std::log(std::max(double(g), 0.0) + kGmsdFloor));
  double f = objective(s, x, g, o);
  if (f < s.best_f) {
    if (!std::isfinite(s.best_f) || f < s.best_f - 1e-3 * std::abs(s.best_f)) s.last_improvement = evaluation;
    s.best_f = f, s.best_g = g;
    std::copy(x, x + 4, s.best_x);
  }
  const int n = int(s.bo->evaluations());
  if (n >= o.evaluations || (o.early_stop && n >= kStallMinimum && n - s.last_improvement >= kStallWindow)) s.done = true;
}

// One candidate per view of the triangle.
void append_candidates(const Search& s, const double x[4], double lambda_min, std::vector<engine::ViewCandidate>& out) {
  auto j = jacobian_of(x, lambda_min);
  for (uint32_t v = 0; v < s.views; ++v)
    out.push_back({{float(j[0]), float(j[1]), float(j[2]), float(j[3])}, s.first_view + v, 0, 0, 0});
}

// A triangle's loss from its views' scores: the RMS of their GMSD (one view: its GMSD).
double combine(const float* scores, uint32_t views) {
  if (views == 1) return scores[0];
  double sum = 0;
  for (uint32_t v = 0; v < views; ++v) sum += double(scores[v]) * scores[v];
  return std::sqrt(sum / views);
}

std::array<double, 4> rotation(double a) { return {std::cos(a), -std::sin(a), std::sin(a), std::cos(a)}; }

std::array<double, 4> multiply(const std::array<double, 4>& a, const std::array<double, 4>& b) {
  return {a[0] * b[0] + a[1] * b[2], a[0] * b[1] + a[1] * b[3], a[2] * b[0] + a[3] * b[2], a[2] * b[1] + a[3] * b[3]};
}

double texel_area(const TriangleViewInput& in, uint32_t t) {
  const uint32_t* f = &in.indices[3 * t];
  double W = in.texture_width, H = in.texture_height;
  double ax = in.uvs[2 * f[0]] * W, ay = in.uvs[2 * f[0] + 1] * H;
  double bx = in.uvs[2 * f[1]] * W, by = in.uvs[2 * f[1] + 1] * H;
  double cx = in.uvs[2 * f[2]] * W, cy = in.uvs[2 * f[2] + 1] * H;
  return 0.5 * std::abs((bx - ax) * (cy - ay) - (cx - ax) * (by - ay));
}

double variance(const std::vector<float>& v) {
  double m = 0, s = 0;
  for (float x : v) m += x;
  m /= double(v.size());
  for (float x : v) s += (x - m) * (x - m);
  return s / double(v.size());
}

}  // namespace

std::array<double, 4> jacobian_of(const double x[4], double lambda_min, double* alpha, double* lambda1,
                                  double* lambda2, double* beta) {
  double a = x[0] * kHalfPi, l1 = lambda_min + x[1] * (1 - lambda_min), l2 = lambda_min + x[2] * (1 - lambda_min),
         b = x[3] * kHalfPi;
  if (alpha) *alpha = a;
  if (lambda1) *lambda1 = l1;
  if (lambda2) *lambda2 = l2;
  if (beta) *beta = b;
  auto V = rotation(b), Vt = rotation(-b);
  auto S = multiply(multiply(V, {l1, 0, 0, l2}), Vt);
  return multiply(rotation(a), S);
}

std::vector<std::vector<double>> measure_triangles(engine::Engine& engine, const TriangleViewInput& input,
                                                   const std::vector<float>& texture, const TriangleStageOptions& o,
                                                   const std::vector<std::array<double, 4>>& jacobians,
                                                   const std::vector<uint32_t>& which) {
  TriangleViews tv = make_triangle_views(input, o.view_size, which, o.max_patches, o.min_texels_per_pixel);
  tv.desc.texture = texture.data(), tv.desc.texture_width = input.texture_width;
  tv.desc.texture_height = input.texture_height;
  auto views = engine.prepare_views(tv.desc);
  // Every view at every Jacobian in one batch: the views are prepared once, not once per
  // Jacobian, and a candidate's score does not depend on the others in its batch (engines
  // chunk a batch as they need).
  const uint32_t nv = uint32_t(tv.desc.views.size());
  std::vector<engine::ViewCandidate> c;
  c.reserve(size_t(nv) * jacobians.size());
  for (const auto& j : jacobians)
    for (uint32_t v = 0; v < nv; ++v) c.push_back({{float(j[0]), float(j[1]), float(j[2]), float(j[3])}, v, 0, 0, 0});
  std::vector<float> g(c.size());
  if (!c.empty()) engine.score_views(*views, c.data(), c.size(), g.data());
  std::vector<std::vector<double>> out(jacobians.size(), std::vector<double>(tv.first_view.size() - 1));
  for (size_t j = 0; j < jacobians.size(); ++j)
    for (size_t k = 0; k < out[j].size(); ++k)
      out[j][k] = combine(&g[j * nv + tv.first_view[k]], tv.first_view[k + 1] - tv.first_view[k]);
  return out;
}

std::vector<double> measure_triangles(engine::Engine& engine, const TriangleViewInput& input,
                                      const std::vector<float>& texture, const TriangleStageOptions& o,
                                      const std::array<double, 4>& j, const std::vector<uint32_t>& which) {
  return measure_triangles(engine, input, texture, o, std::vector<std::array<double, 4>>{j}, which).front();
}

std::vector<TriangleResult> optimize_triangles(engine::Engine& engine, const TriangleViewInput& input,
                                               const std::vector<float>& texture, const TriangleStageOptions& o,
                                               const std::vector<uint32_t>& which, TriangleStageStats* stats) {
  const Stopwatch t_start;
  TriangleStageStats local;
  std::vector<uint32_t> all = which;
  if (all.empty())
    for (uint32_t t = 0; t < input.triangle_count; ++t) all.push_back(t);
  if (!o.epsilons.empty() && o.epsilons.size() < input.triangle_count)
    throw std::invalid_argument("optimize_triangles: epsilons has fewer entries than the mesh has triangles");
  std::vector<TriangleResult> results(all.size());
  const bool overlap = o.overlap == TriangleStageOptions::Overlap::On ||
                       (o.overlap == TriangleStageOptions::Overlap::Auto && engine.device().type != "cpu");

  for (size_t wave_start = 0; wave_start < all.size(); wave_start += o.wave) {
    const size_t wave_end = std::min(all.size(), wave_start + o.wave);
    std::vector<uint32_t> wave(all.begin() + long(wave_start), all.begin() + long(wave_end));
    Stopwatch t0;
    TriangleViews tv = make_triangle_views(input, o.view_size, wave, o.max_patches, o.min_texels_per_pixel);
    engine::ViewSetDesc& desc = tv.desc;
    desc.texture = texture.data(), desc.texture_width = input.texture_width, desc.texture_height = input.texture_height;
    local.host_seconds += t0.seconds();
    t0.restart();
    auto views = engine.prepare_views(desc);
    local.device_seconds += t0.seconds();
    local.views += desc.views.size();

    std::vector<Search> searches(wave.size());
    for (size_t k = 0; k < wave.size(); ++k) {
      Search& s = searches[k];
      s.triangle = wave[k], s.area = texel_area(input, wave[k]);
      s.eps = o.epsilons.empty() ? o.epsilon : o.epsilons[wave[k]];
      s.first_view = tv.first_view[k], s.views = tv.first_view[k + 1] - tv.first_view[k];
      bo::BoOptions bo_options;
      bo_options.dim = 4, bo_options.initial = o.initial;
      bo_options.seed = o.seed * 1000003ull + wave[k];  // per triangle: independent of waves and threads
      s.bo = std::make_unique<bo::BayesOpt>(bo_options);
      const double identity[4] = {0, 1, 1, 0};
      s.bo->set_initial_point(0, identity);
      if (o.start_scale > o.lambda_min && o.start_scale < 1 && o.initial > 1) {
        // The uniform shrink a plain resize would apply: under rate control the bound is set
        // just above its loss, so the search starts from a point known to be (nearly) feasible.
        const double u = (o.start_scale - o.lambda_min) / (1 - o.lambda_min);
        const double shrink[4] = {0, u, u, 0};
        s.bo->set_initial_point(1, shrink);
      }
    }

    // Lockstep rounds over two halves: while the engine scores one half, the host updates
    // and proposes for the other (when `overlap`).
    std::vector<size_t> halves[2];
    for (size_t k = 0; k < searches.size(); ++k) halves[k % 2].push_back(k);
    // Per half: the proposals' candidates (every view of every triangle, in half order) and
    // where each triangle's candidates start.
    struct Batch {
      std::vector<engine::ViewCandidate> candidates;
      std::vector<uint32_t> start;
      std::vector<float> scores, lattice;
    };
    auto propose = [&](std::vector<size_t>& half, Batch& batch) {
      half.erase(std::remove_if(half.begin(), half.end(), [&](size_t k) { return searches[k].done; }), half.end());
#pragma omp parallel for schedule(dynamic, 1)
      for (long i = 0; i < long(half.size()); ++i) {
        Search& s = searches[half[size_t(i)]];
        s.bo->propose([&](const double* x, double m, double sd) { return acquisition(s, x, m, sd, o); }, s.x);
      }
      batch.candidates.clear(), batch.start.clear();
      for (size_t k : half) {
        batch.start.push_back(uint32_t(batch.candidates.size()));
        append_candidates(searches[k], searches[k].x, o.lambda_min, batch.candidates);
      }
      batch.start.push_back(uint32_t(batch.candidates.size()));
    };
    auto update = [&](const std::vector<size_t>& half, const Batch& batch) {
#pragma omp parallel for schedule(dynamic, 1)
      for (long i = 0; i < long(half.size()); ++i) {
        Search& s = searches[half[size_t(i)]];
        const uint32_t first = batch.start[size_t(i)];
        const float lattice = *std::max_element(batch.lattice.begin() + first, batch.lattice.begin() + first + s.views);
        record(s, s.x, combine(&batch.scores[first], s.views), lattice, int(s.bo->evaluations()) + 1, o);
      }
    };
    auto score_async = [&](Batch& batch) {
      batch.scores.resize(batch.candidates.size()), batch.lattice.resize(batch.candidates.size());
      return std::async(overlap ? std::launch::async : std::launch::deferred, [&engine, &views, &batch] {
        Stopwatch t;
        if (!batch.candidates.empty())
          engine.score_views(*views, batch.candidates.data(), batch.candidates.size(), batch.scores.data(), nullptr,
                             batch.lattice.data());
        return t.seconds();
      });
    };

    Batch batch[2];
    t0.restart();
    propose(halves[0], batch[0]);
    local.host_seconds += t0.seconds();
    while (!halves[0].empty() || !halves[1].empty()) {
      for (int h = 0; h < 2; ++h) {
        // batch[h] is proposed; score it while the other half is updated and proposed.
        auto pending = score_async(batch[h]);
        local.evaluations += batch[h].start.empty() ? 0 : batch[h].start.size() - 1;
        local.view_scores += batch[h].candidates.size();
        t0.restart();
        const int other = 1 - h;
        if (!batch[other].candidates.empty()) update(halves[other], batch[other]);
        propose(halves[other], batch[other]);
        local.host_seconds += t0.seconds();
        local.device_seconds += pending.get();
      }
      // Half 1's scores are applied in the next pass (as `other` of h = 0).
      ++local.rounds;
      if (o.progress) {
        size_t done = wave_start;
        for (const Search& s : searches) done += s.done;
        o.progress(done, all.size());
      }
      if (halves[0].empty() && halves[1].empty()) break;
    }

    // Results: the best feasible point, or, when no evaluation met eps, the identity with
    // its measured loss and `feasible` false (never a default passed off as measured).
    // Then the weights of eq. 17 as one more engine batch.
    std::vector<engine::ViewCandidate> weight_batch;
    const int K = o.weight_samples;
    for (size_t k = 0; k < searches.size(); ++k) {
      Search& s = searches[k];
      TriangleResult& r = results[wave_start + k];
      r.feasible = std::isfinite(s.best_f);
      if (!r.feasible) {
        const double identity[4] = {0, 1, 1, 0};
        std::copy(identity, identity + 4, s.best_x);
        s.best_g = s.identity_g;
      }
      auto j = jacobian_of(s.best_x, o.lambda_min, &r.alpha, &r.lambda1, &r.lambda2, &r.beta);
      r.jacobian = j;
      r.rotation = rotation(r.alpha);
      r.stretch = multiply(multiply(rotation(r.beta), {r.lambda1, 0, 0, r.lambda2}), rotation(-r.beta));
      r.gmsd = s.best_g, r.objective = s.best_f, r.texel_area = s.area;
      r.identity_gmsd = s.identity_g;
      r.identity_lattice = s.identity_lattice;
      r.views = int(s.views);
      r.complete = tv.complete[k] != 0;
      r.texels_per_pixel = 0;
      for (uint32_t v = 0; v < s.views; ++v)
        r.texels_per_pixel = std::max(r.texels_per_pixel, double(tv.texels_per_pixel[s.first_view + v]));
      r.evaluations = int(s.bo->evaluations());
      for (int q = 0; q < K; ++q) {  // alpha swept, the rest at the optimum
        double x[4] = {(q + 0.5) / K, s.best_x[1], s.best_x[2], s.best_x[3]};
        append_candidates(s, x, o.lambda_min, weight_batch);
      }
      double shift[3] = {0.5, 0.5, 0.5};
      for (int q = 0; q < K; ++q) {  // lambda1, lambda2, beta swept (Halton), alpha at the optimum
        double h[3];
        bo::halton(uint64_t(q) + 1, 3, shift, h);
        double x[4] = {s.best_x[0], h[0], h[1], h[2]};
        append_candidates(s, x, o.lambda_min, weight_batch);
      }
    }
    std::vector<float> weight_scores(weight_batch.size());
    t0.restart();
    engine.score_views(*views, weight_batch.data(), weight_batch.size(), weight_scores.data());
    local.device_seconds += t0.seconds();
    local.view_scores += weight_batch.size();
    size_t at = 0;
    for (size_t k = 0; k < searches.size(); ++k) {
      const uint32_t nv = searches[k].views;
      std::vector<float> rot(static_cast<size_t>(K)), str(static_cast<size_t>(K));
      for (int q = 0; q < K; ++q, at += nv) rot[size_t(q)] = float(combine(&weight_scores[at], nv));
      for (int q = 0; q < K; ++q, at += nv) str[size_t(q)] = float(combine(&weight_scores[at], nv));
      results[wave_start + k].weight_rotation = variance(rot);
      results[wave_start + k].weight_stretch = variance(str);
    }
  }
  local.wall_seconds = t_start.seconds();
  if (stats) *stats = local;
  return results;
}

}  // namespace uvpress::perceptual
