#include "pipeline/reparam.h"

#include "atlas/charts.h"
#include "atlas/gutter_fill.h"
#include "atlas/pack.h"
#include "atlas/place_texels.h"
#include "atlas/rebake.h"
#include "atlas/rebake_lsq.h"
#include "atlas/rebake_lanczos.h"
#include "atlas/uv_overlap.h"
#include "core/disjoint_sets.h"
#include "core/error.h"
#include "core/quantile.h"
#include "core/stopwatch.h"
#include "core/texture_cost.h"
#include "eval/eval.h"
#include "eval/resize.h"
#include "io/asset.h"
#include "io/gltf_append.h"
#include "io/gltf_prune.h"
#include "io/image_io.h"
#include "perceptual/mesh_stage.h"
#include "perceptual/outline_fit.h"
#include "perceptual/rate_allocation.h"
#include "pipeline/injective_fit.h"
#include "pipeline/isometric_charts.h"
#include "pipeline/texture_costs.h"
#include "perceptual/triangle_view.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <map>
#include <numeric>
#include <set>

namespace uvpress::pipeline {

using json = nlohmann::ordered_json;

namespace {

// One UV set of one primitive: TEXCOORD_n of asset.primitives[primitive].
struct UvSet {
  int primitive = -1, tex_coord = 0;
  bool operator<(const UvSet& o) const { return std::tie(primitive, tex_coord) < std::tie(o.primitive, o.tex_coord); }
};

// A layout: the UV sets and images that must change together. An image sampled through
// several UV sets, or a UV set sampled by several images, ties them into one layout.
struct Layout {
  std::vector<UvSet> uv_sets;
  std::vector<int> images;
  int driver = -1;        // the image whose perceptual loss drives the optimization
  std::string untouched;  // why the layout is left as it is ("" when it is re-parameterized)
};

// What the triangle stage measured over one layout, for the report: how many triangles met
// eps (the rest are kept at the identity, with the identity's measured loss), whether the
// views resolved the source texels, and how far the targets shrink (lambda1 lambda2).
struct TriangleCounts {
  size_t optimized = 0, feasible = 0, resolved = 0, sampled = 0, coarsened = 0, evaluations = 0;
  std::vector<double> infeasible_identity_gmsd, lambda_area;
  std::vector<double> rate_epsilons;  // per triangle under rate control (empty: the fixed epsilon)

  TriangleStageReport report(const perceptual::TriangleStageOptions& t) const {
    TriangleStageReport r;
    r.epsilon = t.epsilon;
    if (!rate_epsilons.empty())
      r.rate_control = TriangleStageReport::RateControl{
          {quantile(rate_epsilons, 0.25), quantile(rate_epsilons, 0.5), quantile(rate_epsilons, 0.75)},
          quantile(rate_epsilons, 1.0)};
    r.evaluations = t.evaluations;
    r.evaluations_mean = optimized ? double(evaluations) / double(optimized) : 0.0;
    r.early_stop = t.early_stop;
    r.view_size = t.view_size;
    r.triangles = optimized;
    r.feasible = feasible;
    r.infeasible = optimized - feasible;
    r.views_resolve_texels = resolved;
    r.sampled_by_patches = sampled;
    r.tiles_coarsened = coarsened;
    r.lambda_area_quartiles = {quantile(lambda_area, 0.25), quantile(lambda_area, 0.5), quantile(lambda_area, 0.75)};
    if (!infeasible_identity_gmsd.empty())
      r.infeasible_identity_gmsd = TriangleStageReport::IdentityGmsd{quantile(infeasible_identity_gmsd, 0.5),
                                                                     quantile(infeasible_identity_gmsd, 1.0)};
    return r;
  }
};

std::vector<Layout> find_layouts(const io::Asset& asset) {
  // Union-find over images (0..I-1) and UV sets (I..).
  std::map<UvSet, int> set_id;
  for (const auto& img : asset.images)
    for (const auto& use : img.uses) set_id.emplace(UvSet{use.primitive, use.tex_coord}, 0);
  const int I = int(asset.images.size());
  int next = I;
  for (auto& [key, id] : set_id) id = next++;
  std::vector<int> parent(static_cast<size_t>(next));
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[size_t(x)] != x) x = parent[size_t(x)] = parent[size_t(parent[size_t(x)])];
    return x;
  };
  for (const auto& img : asset.images)
    for (const auto& use : img.uses) {
      int a = find(img.index), b = find(set_id[{use.primitive, use.tex_coord}]);
      if (a != b) parent[size_t(std::max(a, b))] = std::min(a, b);
    }
  std::map<int, Layout> by_root;
  for (const auto& img : asset.images)
    if (!img.uses.empty()) by_root[find(img.index)].images.push_back(img.index);
  for (const auto& [key, id] : set_id) by_root[find(id)].uv_sets.push_back(key);
  std::vector<Layout> out;
  for (auto& [root, layout] : by_root) {
    // The driver: baseColor first, then emissive, then the first image.
    for (auto role : {io::TextureRole::BaseColor, io::TextureRole::Emissive})
      for (int i : layout.images)
        for (const auto& use : asset.images[size_t(i)].uses)
          if (layout.driver < 0 && use.role == role) layout.driver = i;
    if (layout.driver < 0) layout.driver = layout.images.front();
    for (int i : layout.images)
      for (const auto& use : asset.images[size_t(i)].uses) {
        if (use.tiled && layout.untouched.empty())
          layout.untouched = "image '" + asset.images[size_t(i)].name + "' tiles (UVs outside [0,1] under REPEAT)";
        if (use.transform.present && layout.untouched.empty())
          layout.untouched = "image '" + asset.images[size_t(i)].name + "' is sampled through KHR_texture_transform";
      }
    out.push_back(std::move(layout));
  }
  return out;
}

// A chart in one UV set: its triangles (primitive triangle indices) and welded UV vertices.
struct Chart {
  size_t uv_set = 0;                  // index into Layout::uv_sets
  std::vector<uint32_t> triangles;    // primitive triangle indices
  std::vector<uint32_t> vertices;     // welded UV vertex ids of the set, local order
  std::vector<uint32_t> local;        // 3 local vertex indices per triangle, positive orientation
  std::vector<double> uv;             // input, texel units of the driver (2 per local vertex)
  std::vector<double> positions;      // 3 per local vertex (its welded UV vertex's position)
  std::vector<double> new_uv;         // after the mesh stage, same units
  bool rigid = false;                 // mixed orientation (folded / partly mirrored): not optimized
  bool shared = false;                // shares source texels with another chart: moved with it, unreshaped
};

double signed_area(const double* a, const double* b, const double* c) {
  return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
}

bool has_tangents(const tinygltf::Model& m, const io::Primitive& p) {
  return m.meshes[size_t(p.mesh)].primitives[size_t(p.primitive)].attributes.count("TANGENT") > 0;
}

// One re-parameterized layout's input side, computed once: its charts and the triangle
// stage's results, from which every candidate layout derives its targets.
struct Prepared {
  size_t index = 0;  // into the layouts
  Image driver;
  double W = 0, H = 0;
  std::vector<Chart> charts;
  std::vector<std::vector<uint32_t>> welded_of_vertex;  // per UV set: primitive vertex -> welded UV id
  std::vector<size_t> welded_count;
  std::vector<std::vector<perceptual::TriangleResult>> results;  // per UV set (empty without optimize)
  // The equal-slope allocation (perceptual/rate_allocation.h): each allocated triangle's
  // loss at kSlopeScales, texel area and surface weight, measured once (empty: not
  // computed), and where it sits (UV set, triangle); equal_slope_at() allocates them at a
  // budget.
  perceptual::LossCurves slope_loss;
  std::vector<double> slope_area, slope_weight;
  std::vector<std::pair<size_t, uint32_t>> slope_where;
  double old_used = 0;  // eq. 20: source texels under the input's charts
  size_t rigid = 0;
  TriangleCounts tri;
  // Packing units: charts that share source texels (mirrored halves, instanced parts, two
  // meshes on one atlas region) are packed together, in their input arrangement, so the
  // output keeps the saving the input already had.
  std::vector<std::vector<uint32_t>> units;  // chart indices per unit
  std::vector<uint32_t> unit_of_chart;
  std::vector<double> unit_texels;  // source texel centres under each unit (shared ones once)
  size_t shared_charts = 0;
  // Per packing unit its loss at kSlopeScales, surface weight and source texels, for the
  // equal-slope allocation over whole units (measure_unit_losses; empty: not measured).
  perceptual::LossCurves unit_loss;
  std::vector<double> unit_area, unit_weight;
  double requested_share = 1;  // the requested cost as a share of the source's texels (rate control's; both allocations')
  // ReparamOptions::isometric: the charts flattened once (pipeline/isometric_charts.h), and
  // the packing units with each flattened chart on its own (the others keep their grouping).
  IsometricCharts isometric;
  std::vector<std::vector<uint32_t>> isometric_units;
  std::vector<uint32_t> isometric_unit_of_chart;
};

// Groups the charts of `P` that cover a common source texel centre into packing units and
// marks them `shared`. Texel centres, not conservative footprints: charts that merely touch
// along a texel line do not share a texel.
void find_shared_texels(Prepared& P) {
  const int W = int(P.W), H = int(P.H);
  std::vector<uint32_t> owner(size_t(W) * size_t(H), UINT32_MAX);
  DisjointSets sets(P.charts.size());
  for (uint32_t c = 0; c < P.charts.size(); ++c) {
    const Chart& ch = P.charts[c];
    for (size_t t = 0; t < ch.triangles.size(); ++t) {
      const double* a = &ch.uv[2 * ch.local[3 * t]];
      const double* b = &ch.uv[2 * ch.local[3 * t + 1]];
      const double* d = &ch.uv[2 * ch.local[3 * t + 2]];
      const double area = signed_area(a, b, d);
      if (area == 0) continue;
      const int x0 = std::max(0, int(std::floor(std::min({a[0], b[0], d[0]}) - 0.5)));
      const int x1 = std::min(W - 1, int(std::ceil(std::max({a[0], b[0], d[0]}) - 0.5)));
      const int y0 = std::max(0, int(std::floor(std::min({a[1], b[1], d[1]}) - 0.5)));
      const int y1 = std::min(H - 1, int(std::ceil(std::max({a[1], b[1], d[1]}) - 0.5)));
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          const double p[2] = {x + 0.5, y + 0.5};
          const double w0 = signed_area(b, d, p) / area, w1 = signed_area(d, a, p) / area, w2 = signed_area(a, b, p) / area;
          if (w0 < 0 || w1 < 0 || w2 < 0) continue;
          uint32_t& o = owner[size_t(y) * size_t(W) + size_t(x)];
          if (o == UINT32_MAX) o = c;
          else if (o != c) sets.unite(o, c);
        }
    }
  }
  std::vector<uint32_t> unit_of_root(P.charts.size(), UINT32_MAX);
  P.unit_of_chart.assign(P.charts.size(), 0);
  P.units.clear();
  for (uint32_t c = 0; c < P.charts.size(); ++c) {
    uint32_t& u = unit_of_root[sets.find(c)];
    if (u == UINT32_MAX) u = uint32_t(P.units.size()), P.units.emplace_back();
    P.units[u].push_back(c);
    P.unit_of_chart[c] = u;
  }
  P.shared_charts = 0;
  for (const auto& unit : P.units)
    if (unit.size() > 1)
      for (uint32_t c : unit) P.charts[c].shared = true, ++P.shared_charts;
  P.unit_texels.assign(P.units.size(), 0.0);
  for (uint32_t o : owner)
    if (o != UINT32_MAX) P.unit_texels[P.unit_of_chart[o]] += 1;
}

// Flattens every chart of `P` for the isometric layout (a folded chart too: the solve does
// not start from its UVs, and unfolds it) and groups the packing units, once per layout:
// every candidate built from it (the least-squares variants) reuses the charts.
void prepare_isometric(Prepared& P, const flatten::Options& options) {
  std::vector<ChartGeometry> geometry(P.charts.size());
  for (size_t c = 0; c < P.charts.size(); ++c) {
    const Chart& ch = P.charts[c];
    ChartGeometry& g = geometry[c];
    g.positions = &ch.positions, g.triangles = &ch.local, g.uv = &ch.uv;
  }
  P.isometric = isometric_charts(geometry, options);
  P.isometric_units.clear();
  P.isometric_unit_of_chart.assign(P.charts.size(), 0);
  std::map<uint32_t, uint32_t> unit_of_group;
  for (uint32_t c = 0; c < P.charts.size(); ++c) {
    uint32_t u;
    if (P.isometric.flattened[c]) {
      u = uint32_t(P.isometric_units.size()), P.isometric_units.emplace_back();
    } else {
      auto [it, fresh] = unit_of_group.emplace(P.unit_of_chart[c], uint32_t(P.isometric_units.size()));
      if (fresh) P.isometric_units.emplace_back();
      u = it->second;
    }
    P.isometric_units[u].push_back(c), P.isometric_unit_of_chart[c] = u;
  }
}

// A triangle's share of the screen: its surface area.
double surface_area(const io::Primitive& prim, uint32_t t) {
  const uint32_t* ix = &prim.indices[3 * size_t(t)];
  const float* a = &prim.positions[3 * size_t(ix[0])];
  const float* b = &prim.positions[3 * size_t(ix[1])];
  const float* c = &prim.positions[3 * size_t(ix[2])];
  const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
  return 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

// The budget share below which the allocating plans are also built with their allocation
// made at this share (choose_layout).
constexpr double kHalfShare = 0.5;

// The shrinks at which the equal-slope allocations measure each triangle's loss.
const std::vector<double> kSlopeScales = {0.125, 0.25, 0.35, 0.5, 0.6, 0.707, 0.85, 1.0};

// Each packing unit's loss curve for the equal-slope allocation over whole units
// (perceptual/rate_allocation.h), each kept in its input shape at one uniform scale: the
// only reshaping a unit whose charts share texels (Duck's mirrored halves) allows without
// giving that sharing up, and the plainest one for any chart (no mesh stage, no new
// distortion). A unit's loss at scale s is the surface-weighted mean of its triangles'
// losses at J = s I, measured on the triangle stage's views over an even sample of at most
// kSample of its triangles; its weight is its surface area, its cost its source texels.
void measure_unit_losses(const io::Asset& asset, const Layout& L, Prepared& P, engine::Engine& engine,
                         const std::vector<float>& luminance, const perceptual::TriangleStageOptions& options) {
  constexpr size_t kSample = 48;
  const size_t nu = P.units.size(), ns = kSlopeScales.size();
  if (nu < 2) return;
  // Per unit its triangles (UV set, triangle) in chart order; the sampled ones per UV set.
  std::vector<std::vector<std::pair<size_t, uint32_t>>> tris(nu);
  std::vector<double> surface(nu, 0.0);
  for (size_t u = 0; u < nu; ++u)
    for (uint32_t c : P.units[u])
      for (uint32_t t : P.charts[c].triangles) {
        const size_t si = P.charts[c].uv_set;
        tris[u].push_back({si, t});
        surface[u] += surface_area(asset.primitives[size_t(L.uv_sets[si].primitive)], t);
      }
  std::vector<std::vector<uint32_t>> which(L.uv_sets.size());
  std::vector<std::vector<std::pair<size_t, size_t>>> slot(L.uv_sets.size());  // (unit, k) per sampled triangle
  for (size_t u = 0; u < nu; ++u) {
    const size_t n = tris[u].size(), take = std::min(n, kSample);
    for (size_t k = 0; k < take; ++k) {
      const auto [si, t] = tris[u][k * n / take];
      which[si].push_back(t), slot[si].push_back({u, k});
    }
  }
  // g[u][j]: the unit's surface-weighted loss at kSlopeScales[j].
  std::vector<std::vector<double>> g(nu, std::vector<double>(ns, 0.0));
  std::vector<double> sampled_surface(nu, 0.0);
  for (size_t si = 0; si < L.uv_sets.size(); ++si) {
    if (which[si].empty()) continue;
    const io::Primitive& prim = asset.primitives[size_t(L.uv_sets[si].primitive)];
    const std::vector<float>& uv = prim.uv_sets[size_t(L.uv_sets[si].tex_coord)].uv;
    perceptual::TriangleViewInput in{prim.positions.data(), prim.vertex_count(), prim.indices.data(),
                                     prim.triangle_count(), uv.data(), P.driver.width, P.driver.height};
    std::vector<double> w(which[si].size());
    for (size_t k = 0; k < w.size(); ++k) {
      w[k] = surface_area(prim, which[si][k]);
      sampled_surface[slot[si][k].first] += w[k];
    }
    std::vector<std::array<double, 4>> jacobians;
    for (double s : kSlopeScales) jacobians.push_back({s, 0, 0, s});
    const auto loss = perceptual::measure_triangles(engine, in, luminance, options, jacobians, which[si]);
    for (size_t j = 0; j < ns; ++j)
      for (size_t k = 0; k < loss[j].size(); ++k) g[slot[si][k].first][j] += w[k] * loss[j][k];
  }
  P.unit_loss.scales = kSlopeScales;
  for (size_t u = 0; u < nu; ++u) {
    for (size_t j = 0; j < ns; ++j) P.unit_loss.loss.push_back(sampled_surface[u] > 0 ? g[u][j] / sampled_surface[u] : 0.0);
    P.unit_area.push_back(std::max(P.unit_texels[u], 1.0));
    P.unit_weight.push_back(surface[u]);
  }
}

// The guard's views from afar: eval's 20 cameras with the asset filling views of this many
// pixels a side (three.js's far views in tests/client), where a viewer samples coarse mip
// levels that the near views (every texel resolved) never reach.
constexpr uint32_t kFarViewPixels = 256;

// A candidate layout: the triangle stage's targets with every stretch factor floored at
// `floor` (the paper's targets at lambda_min), with or without its rotations, or no
// reshaping at all (`repack`: the input's charts, only repacked; `unit-scale`: each packing
// unit at a uniform scale of its own). The most aggressive targets are not always the best at a given cost (the mesh stage's compromise and the re-bake both lose
// detail), so reparam builds a few and keeps the one that scores best on screen.
struct Candidate {
  std::string name;
  bool reshape = true;
  double floor = 0;
  // How reshaped charts are re-baked: Lanczos-3 through each triangle's map (atlas/
  // rebake_lanczos.h: as sharp as the resize it competes with; on the demo at half the
  // texels q 0.022 where the area filter gives 0.030), or by least squares (rebake_lsq.h).
  enum class Bake { Lanczos, LeastSquares } bake = Bake::Lanczos;
  bool rotate = true;          // follow the triangle stage's rotations (false: R-bar = I, stretches only)
  bool exact = true;           // unreshaped charts keep their texels (atlas/place_texels.h), else resampled
  bool outline = false;        // reshaped charts keep their input outline (perceptual/outline_fit.h)
  // Targets J = s I from the equal-slope allocation (equal_slope_at) instead of the
  // triangle stage's Jacobians (its weights are kept).
  bool equal_slope = false;
  // The automatic gutter one mip level cleaner (atlas::mip_safe_gutter down to a side of 32
  // texels, at most 32: twice as wide where the cap allows).
  bool wide_gutter = false;
  // The image's mip chain kept whole at the levels the gutter keeps apart (A = the largest
  // power of two <= the gutter that the block divides, atlas::mip_phase_align): every
  // candidate's sides are multiples of A (budget_options), and these also the copied units'
  // translations (atlas::ChartShape::align), so that a copied unit's texels at levels
  // 1..log2 A are the texels of the image it was copied from at those levels, not boxes of
  // another phase.
  bool mip_aligned = false;
  uint32_t mip_depth = 1;  // sides multiples of mip_depth * A (2: one level cleaner than the gutter)
  // The copied units packed at the source's density (atlas::ChartShape::pinned), the others
  // at the packing's scale: the alignment's rounding then shrinks the resampled units, not
  // the copies, which stay bit-exact. It also moves texels from the resampled units to the
  // copies (the unit-scale allocation's largest units), so wherever it pins anything the
  // variant is built with one scale for all as well, and the score decides (choose_layout).
  // Where the copies alone overfill the budget, every unit takes the one scale.
  bool pin_copies = false;
  // Every chart flattened at one density instead (ReparamOptions::isometric).
  bool isometric = false;
  // Charts unreshaped, each packing unit at its own uniform scale (unit_scales_filling).
  bool unit_scale = false;
  // The budget share the equal-slope and unit-scale allocations are made at (0: the
  // requested cost's, Prepared::requested_share); the packer scales the result into the budget.
  double allocation_share = 0;
};

// What one candidate came to, in the output file it was written into.
struct Realized {
  std::string name;
  std::vector<LayoutReport> layouts;  // by layout index (untouched ones as they are)
  std::vector<TextureReport> textures;
  double old_texels = 0, new_texels = 0;
  size_t flips = 0, charts = 0, mesh_failed = 0;
  size_t overlaps_new = 0;           // triangle pairs overlapping in the written UVs, not in the input's
  size_t overlap_fallback_charts = 0;  // charts kept at their input shape because their fit overlapped
  size_t unreshaped_units = 0;       // units whose texels could be copied (cand.exact), before snapping
  size_t pinned_units = 0;           // units packed at the source's density (Candidate::pin_copies)
  double t_mesh = 0, t_pack = 0, t_bake = 0;
  double q = -1;                     // 20-view GMSD of the file as written (-1: not scored)
  // Images encoded as drafts (io::EncodeSettings::draft), with their texels and settings:
  // encoded for good (finish_encoding) only if this candidate is kept.
  struct Draft {
    int image = 0;
    Image texels;
    io::EncodeSettings settings;
  };
  std::vector<Draft> drafts;
};

perceptual::TriangleTarget target_of(const perceptual::TriangleResult& r, double floor, bool rotate) {
  // S-bar = V(beta) diag(l1, l2) V(beta)^T with the stretches floored (eq. 13's factors).
  const double l1 = std::max(r.lambda1, floor), l2 = std::max(r.lambda2, floor);
  const double c = std::cos(r.beta), s = std::sin(r.beta);
  const std::array<double, 4> S{c * c * l1 + s * s * l2, c * s * (l1 - l2), c * s * (l1 - l2), s * s * l1 + c * c * l2};
  return {rotate ? r.rotation : std::array<double, 4>{1, 0, 0, 1}, S, r.weight_rotation, r.weight_stretch};
}

// Whether any texture sampling the layout's images repeats along u (S) and v (T): only
// then may a chart near one image edge be read across it from the far one (atlas::PackOptions).
std::array<bool, 2> repeating_axes(const io::Asset& asset, const Layout& L) {
  std::array<bool, 2> r{false, false};
  for (int i : L.images)
    for (const io::ImageUse& use : asset.images[size_t(i)].uses)
      r[0] |= use.wrap_s == atlas::kWrapRepeat, r[1] |= use.wrap_t == atlas::kWrapRepeat;
  return r;
}

// The smallest singular value of the map old -> new of one triangle (both in texels).
double smallest_stretch(const double* a, const double* b, const double* c, const double* A, const double* B,
                       const double* C) {
  const double e[4] = {b[0] - a[0], c[0] - a[0], b[1] - a[1], c[1] - a[1]};  // old edges as columns
  const double f[4] = {B[0] - A[0], C[0] - A[0], B[1] - A[1], C[1] - A[1]};  // new edges
  const double det = e[0] * e[3] - e[1] * e[2];
  if (!(std::abs(det) > 1e-12)) return 0;
  // M = F E^-1; sigma_min^2 = (|M|_F^2 - sqrt(|M|_F^4 - 4 det(M)^2)) / 2.
  const double m[4] = {(f[0] * e[3] - f[1] * e[2]) / det, (-f[0] * e[1] + f[1] * e[0]) / det,
                       (f[2] * e[3] - f[3] * e[2]) / det, (-f[2] * e[1] + f[3] * e[0]) / det};
  const double fro = m[0] * m[0] + m[1] * m[1] + m[2] * m[2] + m[3] * m[3], dm = m[0] * m[3] - m[1] * m[2];
  return std::sqrt(std::max(0.0, 0.5 * (fro - std::sqrt(std::max(0.0, fro * fro - 4 * dm * dm)))));
}

// Per UV set and triangle, the equal-slope allocation's isotropic scale at a budget of
// `share` of the source's texels under the allocated triangles (1 where none was allocated),
// and its figures. The losses were measured once (measure_slope_losses); the allocation is a
// one-multiplier search, cheap enough to redo for each candidate.
struct EqualSlope {
  std::vector<std::vector<double>> scale;
  EqualSlopeReport report;
};
EqualSlope equal_slope_at(const Prepared& P, double share) {
  const perceptual::RateAllocation alloc = perceptual::allocate_by_equal_slope(P.slope_loss, P.slope_area, P.slope_weight, share);
  EqualSlope e;
  e.scale.resize(P.results.size());
  for (size_t si = 0; si < P.results.size(); ++si) e.scale[si].assign(P.results[si].size(), 1.0);
  for (size_t k = 0; k < P.slope_where.size(); ++k) e.scale[P.slope_where[k].first][P.slope_where[k].second] = alloc.scale[k];
  e.report = {share, alloc.spent, alloc.multiplier,
              {quantile(alloc.scale, 0.25), quantile(alloc.scale, 0.5), quantile(alloc.scale, 0.75)}};
  return e;
}

// The packing budget of a candidate: --cost of the source's image texels (or --size), the
// gutter as asked or mip-safe for the image the budget buys (its texels are known before
// packing: --cost of the source's, --size N at the source's aspect; --max-gmsd bakes at the
// source's size and shrinks the gutters with the image). The caller sets s_max and edges.
atlas::BudgetOptions budget_options(const ReparamOptions& o, const Candidate& cand, double W, double H) {
  atlas::BudgetOptions budget;
  budget.cost = o.max_gmsd > 0 ? 1.0 : o.cost, budget.size = o.max_gmsd > 0 ? 0 : o.size;
  budget.pot = o.power_of_two;
  budget.keep_aspect = o.keep_aspect;
  budget.measure = atlas::CostMeasure::ImageTexels;  // --cost is about texture memory
  const double budget_texels = o.max_gmsd > 0 ? double(W) * H
                               : o.size > 0    ? double(o.size) * o.size * std::min(W, H) / std::max(W, H)
                                               : o.cost * W * H;
  budget.pack.gutter = o.gutter != ReparamOptions::kAutoGutter ? o.gutter
                       : cand.wide_gutter                      ? atlas::mip_safe_gutter(budget_texels, 32, 4, 32)
                                                               : atlas::mip_safe_gutter(budget_texels);
  budget.pack.block = o.block;
  // Sides multiples of the gutter's power of two (mip-aligned candidates: of a multiple of
  // it), so that each mip level the gutter keeps clean is exact 2 x 2 boxes of the one above:
  // an odd side halves to texels of 2.003 that drift against level 0 (Fox's 717 x 717), and
  // the gutter's fill and coarsen_gutter's flat blocks then no longer average as planned.
  // At least four of them a side: a tiny budget under a wide gutter would otherwise round a
  // side up past the budget (SizeRule::dims floors the shorter side at one multiple). Not
  // under --size, whose side is the user's (nor are the aligned variants built there).
  if (o.size > 0) return budget;
  uint32_t m = (cand.mip_aligned ? cand.mip_depth : 1) * atlas::mip_phase_align(budget.pack.gutter, budget.pack.block);
  while (m > 1 && 4.0 * m > std::sqrt(budget_texels) && (m / 2) % std::max(1u, o.block) == 0) m /= 2;
  budget.side_multiple = m;
  return budget;
}

// Uniform scales per packing unit (Prepared::unit_loss), relative to the largest: the
// equal-slope allocation at the requested cost (Prepared::requested_share) or at the
// candidate's allocation_share, which the packer scales whole to the budget. Where that
// leaves budget unspent (the largest unit already at the source density: the packer stops
// there), the allocation's share c is raised by bisection until the units just fill the
// budget, so the smaller ones get the texels back.
// A curve point below the requested cost keeps the requested cost's shape, scaled down: the
// layout reparam chose, at another budget. The probe packing ignores whole-texel snapping
// and the copies' edge ring, which realize() adds; 10 steps of bisection.
struct UnitScales {
  std::vector<double> scale;  // per unit, the largest 1
  double cost = 0;            // the allocation's share of the units' source texels
};
UnitScales unit_scales_filling(const Prepared& P, const io::Asset& asset, const Layout& L, const ReparamOptions& o,
                               const Candidate& cand) {
  auto scales_at = [&P](double c) {
    std::vector<double> k = perceptual::allocate_by_equal_slope(P.unit_loss, P.unit_area, P.unit_weight, c).scale;
    const double top = *std::max_element(k.begin(), k.end());
    for (double& x : k) x /= top;
    return k;
  };
  atlas::BudgetOptions budget = budget_options(o, cand, P.W, P.H);
  budget.s_max = 1;
  const auto repeats = repeating_axes(asset, L);
  budget.pack.edge_x = atlas::edge_gutter(budget.pack.gutter, repeats[0]);
  budget.pack.edge_y = atlas::edge_gutter(budget.pack.gutter, repeats[1]);
  // Whether the units at scales k fit the budget with room to spare (packed at s_max = 1).
  // The allocation is piecewise constant in its share (losses measured at a few shrinks),
  // so the bisection asks about the same scales again and again (Fox: 5 of its 12 packings
  // were repeats): each answer is kept.
  std::vector<std::pair<std::vector<double>, bool>> answered;
  auto spare = [&](const std::vector<double>& k) {
    for (const auto& [seen, fits] : answered)
      if (seen == k) return fits;
    std::vector<atlas::ChartShape> shapes(P.units.size());
    for (size_t u = 0; u < P.units.size(); ++u)
      for (uint32_t c : P.units[u]) {
        const uint32_t base = uint32_t(shapes[u].points.size() / 2);
        for (double x : P.charts[c].uv) shapes[u].points.push_back(x * k[u]);
        for (uint32_t l : P.charts[c].local) shapes[u].triangles.push_back(base + l);
      }
    const atlas::AtlasChoice choice = atlas::choose_atlas(shapes, P.driver.width, P.driver.height, P.old_used, budget);
    answered.push_back({k, choice.packing.ok && choice.packing.scale >= 1 - 1e-3});
    return answered.back().second;
  };
  double lo = cand.allocation_share > 0 ? cand.allocation_share : P.requested_share, hi = 1;
  UnitScales best{scales_at(lo), lo};
  if (!spare(best.scale)) return best;  // the packer scales it down whole
  if (std::vector<double> all = scales_at(hi); spare(all)) return {all, hi};  // the whole source fits: the repack
  for (int i = 0; i < 10; ++i) {
    const double mid = std::sqrt(lo * hi);
    std::vector<double> k = scales_at(mid);
    if (spare(k)) lo = mid, best = {std::move(k), mid};
    else hi = mid;
  }
  return best;
}

// Whether the units' allocation at share c leaves any unit below 0.99 of the largest.
bool unit_scales_differ(const Prepared& P, double c) {
  if (P.unit_loss.loss.empty()) return false;
  const perceptual::RateAllocation a = perceptual::allocate_by_equal_slope(P.unit_loss, P.unit_area, P.unit_weight, c);
  const double top = *std::max_element(a.scale.begin(), a.scale.end());
  return *std::min_element(a.scale.begin(), a.scale.end()) < 0.99 * top;
}

// A new palette's weights (io::EncodeSettings::importance): full for the texels that a
// chart's bilinear taps read at level 0 (its footprint and the ring around it, across an edge
// that a sampler repeats across), a sixteenth for the gutter, which only coarse mip levels
// see, averaged (atlas::coarsen_gutter).
std::vector<uint8_t> palette_importance(const std::vector<uint8_t>& footprint, uint32_t width, uint32_t height,
                                        bool wrap_x, bool wrap_y) {
  std::vector<uint8_t> weight(size_t(width) * height, 16);
  if (footprint.size() != weight.size()) return {};
  const int W = int(width), H = int(height);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      if (!footprint[size_t(y) * W + x]) continue;
      for (int v = y - 1; v <= y + 1; ++v)
        for (int u = x - 1; u <= x + 1; ++u) {
          if ((!wrap_x && (u < 0 || u >= W)) || (!wrap_y && (v < 0 || v >= H))) continue;
          weight[size_t((v + H) % H) * W + size_t((u + W) % W)] = 255;
        }
    }
  return weight;
}

// Builds one candidate into `file` (a copy of the input): mesh stage per chart, packing
// into the budget, re-bake of every image of every prepared layout, new UV accessors.
Realized realize(const io::Asset& asset, const std::vector<Layout>& layouts, const std::vector<Prepared>& prepared,
                 const std::vector<LayoutReport>& layout_base, io::GltfFile& file, engine::Engine& engine,
                 const ReparamOptions& o, const Candidate& cand, const Progress& progress, json& warnings) {
  Realized out;
  out.name = cand.name;
  out.layouts = layout_base;
  for (const Prepared& P : prepared) {
    const size_t li = P.index;
    const Layout& L = layouts[li];
    const std::vector<Chart>& charts = P.charts;
    const double W = P.W, H = P.H;
    LayoutReport& lr = out.layouts[li];
    size_t layout_flips = 0, mesh_failed = 0, overlap_fallback_pairs = 0, outline_kept = 0, outline_failed = 0;
    const bool slope = cand.equal_slope && !P.slope_where.empty();
    EqualSlope equal_slope;
    if (slope) equal_slope = equal_slope_at(P, cand.allocation_share > 0 ? cand.allocation_share : P.requested_share),
               lr.equal_slope = equal_slope.report;
    UnitScales unit_scales;
    if (cand.unit_scale && !P.unit_loss.loss.empty()) {
      unit_scales = unit_scales_filling(P, asset, L, o, cand);
      const auto& k = unit_scales.scale;
      lr.unit_scale = UnitScaleReport{unit_scales.cost, k.size(), {quantile(k, 0.25), quantile(k, 0.5), quantile(k, 0.75)},
                                      *std::min_element(k.begin(), k.end())};
    }
    double outline_blend = 0;

    // Mesh stage per chart. Weights floored relative to the whole layout's mean (not only
    // the chart's): a chart of flat signal has weights near 0 everywhere and would follow
    // its targets only at w / (w + w_rs) per iteration.
    Stopwatch t0;
    perceptual::MeshStageOptions mesh_options;
    {
      double sum = 0;
      size_t n = 0;
      for (const auto& set : P.results)
        for (const auto& r : set)
          if (r.evaluations > 0 && std::isfinite(r.weight_rotation) && std::isfinite(r.weight_stretch))
            sum += r.weight_rotation + r.weight_stretch, n += 2;
      mesh_options.weight_floor = n ? 1e-3 * sum / double(n) : 0;
    }
    std::vector<std::vector<double>> new_uv_of(charts.size());
    std::vector<std::string> overlapped;  // charts fallen back to their input shape, with their new pairs
    // Packing units: charts that share source texels move together, in their input
    // arrangement, unless the isometric layout gives each of them texels of its own.
    const bool isometric = cand.isometric && !P.isometric.uv.empty();
    const auto& units = isometric ? P.isometric_units : P.units;
    const auto& unit_of_chart = isometric ? P.isometric_unit_of_chart : P.unit_of_chart;
    if (isometric) {
      new_uv_of = P.isometric.uv;
      const size_t flat = size_t(std::count(P.isometric.flattened.begin(), P.isometric.flattened.end(), 1));
      lr.isometric = IsometricReport{flat, charts.size() - flat, P.isometric.filled_holes, P.isometric.texels_per_area};
    }
    const std::string mesh_stage = "mesh stage (" + cand.name + ", layout " + std::to_string(li) + ")";
    if (progress && cand.reshape && !isometric) progress(mesh_stage, 0, charts.size());
    for (size_t c = 0; c < charts.size() && !isometric; ++c) {
      const Chart& ch = charts[c];
      if (!cand.reshape || P.results[ch.uv_set].empty() || ch.rigid || ch.shared) {
        new_uv_of[c] = ch.uv;
        // The unit's uniform scale (about the origin: packing places it), 1 kept exact.
        const double k = unit_scales.scale.empty() ? 1.0 : unit_scales.scale[unit_of_chart[c]];
        if (k != 1.0)
          for (double& x : new_uv_of[c]) x *= k;
        continue;
      }
      std::vector<perceptual::TriangleTarget> targets;
      targets.reserve(ch.triangles.size());
      for (uint32_t t : ch.triangles) {
        const perceptual::TriangleResult& r = P.results[ch.uv_set][t];
        if (slope) {
          const double k = equal_slope.scale[ch.uv_set][t];
          if (cand.floor > 0) {
            // The triangle stage's stretch shape (floored, unrotated) at the allocation's area.
            perceptual::TriangleTarget shaped = target_of(r, cand.floor, false);
            const double det = shaped.stretch[0] * shaped.stretch[3] - shaped.stretch[1] * shaped.stretch[2];
            const double f = det > 0 ? k / std::sqrt(det) : k;
            for (double& v : shaped.stretch) v *= f;
            targets.push_back(shaped);
          } else {
            targets.push_back({{1, 0, 0, 1}, {k, 0, 0, k}, r.weight_rotation, r.weight_stretch});
          }
        } else {
          targets.push_back(target_of(r, cand.floor, cand.rotate));
        }
      }
      // A fit that runs the chart over itself is dropped for the input shape (injective_fit.h).
      InjectiveFit injective = fit_chart_injective(ch.uv, ch.local, targets, mesh_options);
      perceptual::MeshStageResult& fit = injective.fit;
      new_uv_of[c] = std::move(fit.uv);
      // A failed factorization leaves the chart at its input (or last accepted, flip-free)
      // shape: said in the report and as a warning, never passed off as optimized.
      if (fit.failed()) {
        ++mesh_failed;
        if (mesh_failed == 1)
          warnings.push_back(cand.name + ": layout " + std::to_string(li) + " chart " + std::to_string(c) + ": mesh stage " + fit.failure);
      }
      if (injective.fell_back()) {
        overlap_fallback_pairs += injective.overlap_pairs;
        overlapped.push_back(std::to_string(c) + " (" + std::to_string(injective.overlap_pairs) + ")");
      } else if (cand.outline && fit.status == perceptual::MeshStageStatus::Optimized) {
        // The reshaped chart re-embedded in its input outline, so that it packs as the input
        // did; kept only where that neither folds nor runs the chart over itself.
        perceptual::OutlineFit kept = perceptual::keep_outline(ch.uv, new_uv_of[c], ch.local);
        if (kept.ok() && atlas::find_new_overlaps(ch.uv.data(), kept.uv.data(), ch.local.data(), ch.local.size() / 3).empty()) {
          new_uv_of[c] = std::move(kept.uv);
          ++outline_kept;
          outline_blend += kept.blend;
        } else {
          ++outline_failed;
        }
      }
      if (progress) progress(mesh_stage, c + 1, charts.size());
    }
    if (!overlapped.empty()) {
      std::string list;
      for (const auto& c : overlapped) list += (list.empty() ? "" : ", ") + c;
      warnings.push_back(cand.name + ": layout " + std::to_string(li) + ": " + (overlapped.size() == 1 ? "chart " : "charts ") +
                         list + " (new overlapping triangle pairs) ran over " + (overlapped.size() == 1 ? "itself" : "themselves") +
                         " in the mesh stage: kept at the input shape");
    }
    // No triangle may flip relative to the input (a flattened chart: relative to the
    // chart's orientation, which unfolds a folded input).
    for (size_t c = 0; c < charts.size(); ++c) {
      const Chart& ch = charts[c];
      for (size_t t = 0; t < ch.triangles.size(); ++t) {
        const uint32_t* l = &ch.local[3 * t];
        double before = isometric && P.isometric.flattened[c] ? 1.0 : signed_area(&ch.uv[2 * l[0]], &ch.uv[2 * l[1]], &ch.uv[2 * l[2]]);
        double after = signed_area(&new_uv_of[c][2 * l[0]], &new_uv_of[c][2 * l[1]], &new_uv_of[c][2 * l[2]]);
        if ((before > 0 && after <= 0) || (before < 0 && after >= 0)) ++layout_flips;
      }
    }
    out.t_mesh += t0.seconds();

    // The packing scale may grow until the layout fills the budget, but not past the point
    // where the densest triangles (area-weighted 98th percentile) get more texels than the
    // source has in every direction (their smallest singular value of old -> new reaches
    // 1): beyond that, texels would only magnify. An anisotropic target (one stretch near 1,
    // the other small) may thus be magnified along its long axis while its short axis gains.
    double s_max = 1;
    {
      std::vector<std::pair<double, double>> sigma;  // (smallest singular value, old area)
      double total = 0;
      for (size_t c = 0; c < charts.size(); ++c)
        for (size_t t = 0; t < charts[c].triangles.size(); ++t) {
          const uint32_t* l = &charts[c].local[3 * t];
          const auto& u = charts[c].uv;
          const auto& v = new_uv_of[c];
          const double sm = smallest_stretch(&u[2 * l[0]], &u[2 * l[1]], &u[2 * l[2]], &v[2 * l[0]], &v[2 * l[1]], &v[2 * l[2]]);
          const double area = std::abs(signed_area(&u[2 * l[0]], &u[2 * l[1]], &u[2 * l[2]]));
          if (sm > 0) sigma.push_back({sm, area}), total += area;
        }
      std::sort(sigma.begin(), sigma.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
      double above = 0;
      for (const auto& [sm, area] : sigma) {
        above += area;
        if (above >= 0.02 * total) {
          s_max = 1 / sm;
          break;
        }
      }
      s_max = std::clamp(s_max, 1.0, 1.0 / o.triangle.lambda_min);
    }

    // Pack into the budget (eq. 20-21).
    t0.restart();
    std::vector<atlas::ChartShape> shapes(units.size());
    for (size_t u = 0; u < units.size(); ++u)
      for (uint32_t c : units[u]) {
        const uint32_t base = uint32_t(shapes[u].points.size() / 2);
        shapes[u].points.insert(shapes[u].points.end(), new_uv_of[c].begin(), new_uv_of[c].end());
        for (uint32_t l : charts[c].local) shapes[u].triangles.push_back(base + l);
      }
    atlas::BudgetOptions budget = budget_options(o, cand, W, H);
    budget.s_max = s_max;
    const uint32_t gutter = budget.pack.gutter;
    const uint32_t mip_align = cand.mip_aligned ? atlas::mip_phase_align(gutter, budget.pack.block) : 1;
    lr.mip_align = mip_align, lr.side_multiple = budget.side_multiple;
    // Every chart brings what the source has around it into half the gutter (whole-texel
    // copies their ring of the source's own neighbours, re-baked charts their maps extended,
    // RebakeOptions::surround): bilinear taps just past a chart's edge, and coarse mip
    // levels at its edge, then blend in what they blend in the input.
    const uint32_t copy_ring = gutter / 2;
    const uint32_t edge_ring = std::min(1u, copy_ring);  // what must fit inside the image
    std::vector<char> unit_exact(units.size(), 0);
    if (o.exact_texels && cand.exact)
      for (size_t u = 0; u < units.size(); ++u) {
        unit_exact[u] = 1;
        for (uint32_t c : units[u]) unit_exact[u] &= char(new_uv_of[c] == charts[c].uv);
        shapes[u].snap = unit_exact[u] != 0;  // so that the atlas chosen has room for whole-texel origins
        shapes[u].align = mip_align;
        out.unreshaped_units += size_t(unit_exact[u]);
      }
    // The image edges: half the gutter on an axis a sampler repeats across, else none, but
    // room for the copies' first ring (bilinear taps at level 0), which clamping would
    // replace by the chart's own edge texels (unless the unit spans the whole source: then
    // its ring lies outside the source too).
    const auto repeats = repeating_axes(asset, L);
    uint32_t ring = 0;
    for (size_t u = 0; u < units.size(); ++u) {
      if (!unit_exact[u]) continue;
      double lo[2] = {W, H}, hi[2] = {0, 0};
      for (uint32_t c : units[u])
        for (size_t k = 0; k < charts[c].uv.size(); k += 2)
          for (int a = 0; a < 2; ++a) lo[a] = std::min(lo[a], charts[c].uv[k + a]), hi[a] = std::max(hi[a], charts[c].uv[k + a]);
      if (lo[0] > 0.5 || lo[1] > 0.5 || hi[0] < W - 0.5 || hi[1] < H - 0.5) ring = edge_ring;
    }
    budget.pack.edge_x = std::max(ring, atlas::edge_gutter(gutter, repeats[0]));
    budget.pack.edge_y = std::max(ring, atlas::edge_gutter(gutter, repeats[1]));
    // Candidate::pin_copies: the copies at the source's density, the other units at the
    // packing's scale; one scale for all where the copies alone overfill the budget.
    for (size_t u = 0; u < units.size(); ++u) shapes[u].pinned = cand.pin_copies && unit_exact[u];
    const auto is_pinned = [](const atlas::ChartShape& c) { return c.pinned; };
    atlas::AtlasChoice choice = atlas::choose_atlas(shapes, P.driver.width, P.driver.height, P.old_used, budget);
    if (!choice.packing.ok && std::any_of(shapes.begin(), shapes.end(), is_pinned)) {
      for (atlas::ChartShape& c : shapes) c.pinned = false;
      choice = atlas::choose_atlas(shapes, P.driver.width, P.driver.height, P.old_used, budget);
    }
    const size_t pinned_units = size_t(std::count_if(shapes.begin(), shapes.end(), is_pinned));
    const bool pinned = pinned_units > 0;
    out.pinned_units += pinned_units;
    if (!choice.packing.ok)
      throw InputError(file.path, "the charts of layout " + std::to_string(li) + " do not fit any atlas within the budget");
    // Units whose charts keep their shape keep their texels (atlas/place_texels.h): the
    // source resized once to Rw x Rh at the packing scale (floored to whole texels, so the
    // scale per axis is Rw / W, Rh / H), the units' points scaled to that grid and packed
    // with whole-texel translations into the same atlas; a little smaller when snapping
    // does not fit. Pinned, they were packed on the source's own grid already.
    std::vector<std::array<double, 2>> unit_factor(units.size(), {1.0, 1.0});
    uint32_t Rw = 0, Rh = 0;
    if (pinned) {
      Rw = uint32_t(W), Rh = uint32_t(H);
    } else if (std::find(unit_exact.begin(), unit_exact.end(), 1) != unit_exact.end()) {
      bool placed = false;
      for (int attempt = -1; attempt < 12 && !placed; ++attempt) {
        double s = choice.packing.scale * std::pow(0.99, std::max(attempt, 0));
        if (attempt < 0) {
          // First one whole texel up, when the bisection stopped within its tolerance of it
          // (the demo's sheet: 361 texels of a 362-texel image at 0.70702, q 0.0240 vs 0.0233).
          const double side = std::max(W, H), up = (std::floor(side * s + 1e-9) + 1) / side;
          if (up > s * 1.002 || up > budget.s_max) continue;
          s = up;
        }
        Rw = std::max(1u, uint32_t(std::floor(W * s + 1e-9))), Rh = std::max(1u, uint32_t(std::floor(H * s + 1e-9)));
        std::vector<atlas::ChartShape> snapped = shapes;
        for (size_t u = 0; u < units.size(); ++u) {
          if (!unit_exact[u]) continue;
          unit_factor[u] = {Rw / W / s, Rh / H / s};
          for (size_t k = 0; k < snapped[u].points.size(); k += 2)
            snapped[u].points[k] *= unit_factor[u][0], snapped[u].points[k + 1] *= unit_factor[u][1];
          snapped[u].snap = true;
        }
        atlas::Packing q = atlas::pack_charts(snapped, choice.packing.width, choice.packing.height, s, budget.pack);
        if (q.ok) choice.packing = std::move(q), shapes = std::move(snapped), placed = true;
      }
      if (!placed) {  // keep the packing found (snapped origins, resampled texels)
        std::fill(unit_exact.begin(), unit_exact.end(), 0);
        Rw = Rh = 0;
        std::fill(unit_factor.begin(), unit_factor.end(), std::array<double, 2>{1.0, 1.0});
        warnings.push_back(cand.name + ": layout " + std::to_string(li) + ": unreshaped charts could not be snapped to whole texels; resampled");
      }
    }
    const auto& packing = choice.packing;
    // New UVs per primitive vertex (vertices no triangle uses keep theirs).
    std::vector<std::vector<float>> new_uv(L.uv_sets.size()), welded_new(L.uv_sets.size());
    for (size_t si = 0; si < L.uv_sets.size(); ++si) welded_new[si].assign(2 * P.welded_count[si], 0.0f);
    for (size_t c = 0; c < charts.size(); ++c)
      for (size_t v = 0; v < charts[c].vertices.size(); ++v) {
        const auto& f = unit_factor[unit_of_chart[c]];
        auto uv = packing.map_uv(unit_of_chart[c], f[0] * new_uv_of[c][2 * v], f[1] * new_uv_of[c][2 * v + 1]);
        welded_new[charts[c].uv_set][2 * charts[c].vertices[v]] = float(uv[0]);
        welded_new[charts[c].uv_set][2 * charts[c].vertices[v] + 1] = float(uv[1]);
      }
    for (size_t si = 0; si < L.uv_sets.size(); ++si) {
      const io::Primitive& prim = asset.primitives[size_t(L.uv_sets[si].primitive)];
      new_uv[si] = prim.uv_sets[size_t(L.uv_sets[si].tex_coord)].uv;
      for (size_t v = 0; v < prim.vertex_count(); ++v) {
        uint32_t w = P.welded_of_vertex[si][v];
        if (w == UINT32_MAX) continue;
        new_uv[si][2 * v] = welded_new[si][2 * w], new_uv[si][2 * v + 1] = welded_new[si][2 * w + 1];
      }
    }
    out.t_pack += t0.seconds();
    lr.pack_seconds = t0.seconds();

    // The invariant, on the UVs as written: no two triangles of the layout overlap unless
    // they did in the input. The packer keeps its units' footprints apart and a unit's
    // charts as the input had them, so a new overlap here is a bug, never written.
    size_t overlaps_new = 0;
    {
      std::vector<double> before, after;
      std::vector<uint32_t> triangles;
      for (size_t si = 0; si < L.uv_sets.size(); ++si) {
        const io::Primitive& prim = asset.primitives[size_t(L.uv_sets[si].primitive)];
        const std::vector<float>& old_uv = prim.uv_sets[size_t(L.uv_sets[si].tex_coord)].uv;
        const uint32_t base = uint32_t(before.size() / 2);
        before.insert(before.end(), old_uv.begin(), old_uv.end());
        after.insert(after.end(), new_uv[si].begin(), new_uv[si].end());
        for (size_t k = 0; k < 3 * prim.triangle_count(); ++k) triangles.push_back(base + prim.indices[k]);
      }
      overlaps_new = atlas::find_new_overlaps(before.data(), after.data(), triangles.data(), triangles.size() / 3).size();
      if (overlaps_new)
        warnings.push_back(cand.name + ": layout " + std::to_string(li) + ": " + std::to_string(overlaps_new) +
                           " pairs of triangles overlap in the new UVs that did not in the input (layout rejected)");
    }

    // Re-bake every image of the layout into the new UVs, at the driver's new density.
    t0.restart();
    std::vector<atlas::RebakeMesh> meshes;
    for (size_t si = 0; si < L.uv_sets.size(); ++si) {
      const io::Primitive& prim = asset.primitives[size_t(L.uv_sets[si].primitive)];
      meshes.push_back({prim.indices.data(), prim.indices.size(), prim.uv_sets[size_t(L.uv_sets[si].tex_coord)].uv.data(),
                        new_uv[si].data(), prim.vertex_count()});
    }
    size_t baked_count = 0, exact_texels = 0;
    const std::string bake_stage = "re-bake (" + cand.name + ", layout " + std::to_string(li) + ")";
    if (progress) progress(bake_stage, 0, L.images.size());
    for (int i : L.images) {
      const io::AssetImage& img = asset.images[size_t(i)];
      const std::string name = file.path + ": image " + std::to_string(i);
      Image source = i == L.driver ? P.driver : io::decode_image(file.image_bytes[size_t(i)], name);
      atlas::RebakeOptions ro;
      ro.width = std::max(1u, uint32_t(std::lround(double(packing.width) * source.width / W)));
      ro.height = std::max(1u, uint32_t(std::lround(double(packing.height) * source.height / H)));
      ro.role = atlas::RebakeRole::Color;
      for (const auto& use : img.uses) {
        // A tangent-space normal map is rotated into the new UV frame, which is the frame a
        // renderer derives (MikkTSpace) when the mesh has no TANGENT attribute. With stored
        // tangents the frame stays the old one, so the texels must stay as they are.
        if (use.role == io::TextureRole::Normal)
          ro.role = has_tangents(file.model, asset.primitives[size_t(use.primitive)]) ? atlas::RebakeRole::Data
                                                                                      : atlas::RebakeRole::Normal;
        else if (io::color_space_of(use.role) == ColorSpace::Linear && ro.role == atlas::RebakeRole::Color)
          ro.role = atlas::RebakeRole::Data;
        ro.wrap_s = use.wrap_s, ro.wrap_t = use.wrap_t;
      }
      ro.surround = copy_ring;
      // Images whose every unit's texels are copied below (atlas/place_texels.h) need only
      // the area bake, for the gutters: a sharper bake there would be overwritten.
      const bool copies = Rw > 0 && source.width == P.driver.width && source.height == P.driver.height &&
                          ro.role != atlas::RebakeRole::Normal;
      const bool all_copied = copies && std::find(unit_exact.begin(), unit_exact.end(), 0) == unit_exact.end();
      atlas::RebakeStats coverage;
      // The least-squares bake starts from the Lanczos one and keeps its surround (the
      // solve itself only reaches one texel past each chart).
      Image baked = all_copied ? atlas::rebake(source, meshes, ro, engine, &coverage)
                               : atlas::rebake_lanczos(source, meshes, ro, engine, &coverage);
      if (cand.bake == Candidate::Bake::LeastSquares && ro.role != atlas::RebakeRole::Normal) {
        atlas::LsqBakeStats lsq;
        baked = atlas::rebake_least_squares(source, meshes, ro, baked, &lsq, {}, &coverage.coverage);
        if (!lsq.solved) warnings.push_back(cand.name + ": image " + std::to_string(i) + ": the least-squares bake did not converge");
      }
      // Unreshaped units: their texels copied from the source resized like a user would
      // (Lanczos-3 in stored values; pinned, the source itself), on the same grid. Only for
      // images at the driver's size (others are not on that grid) and not for normal maps (a
      // quarter turn must rotate their vectors: the re-bake does that).
      size_t copied = 0;
      if (copies) {
        const Image resized = Rw == source.width && Rh == source.height ? source : eval::resize_lanczos3(source, Rw, Rh, false);
        std::vector<uint8_t>& known = coverage.coverage;  // the bake's texels, then the copies'
        for (size_t u = 0; u < units.size(); ++u)
          if (unit_exact[u]) copied += atlas::copy_chart_texels(resized, shapes[u], packing, u, copy_ring, baked, &known);
        // The gutter filled again from what is now at the charts' edges: the copies (and
        // their ring of the source's own neighbours), not the bake they replaced.
        if (copied) atlas::fill_gutter(baked, known, ro.role == atlas::RebakeRole::Color, atlas::fill_ring(ro));
      }
      exact_texels += copied;
      const std::vector<uint8_t> old_bytes = file.image_bytes[size_t(i)];
      // Written as the input was (its codec, palette, JPEG quality and subsampling): a
      // re-baked texture costs what its author accepted for it. A PNG is drafted (the same
      // texels, one fast zlib pass): most candidates are only scored, and the strongest
      // encoding was 4-7 % of a run (Fox, the truck) spent on bytes nobody kept.
      io::EncodeSettings settings = io::encode_settings_of(old_bytes);
      settings.draft = settings.format == "png";
      // The gutter's detail that no mip level reads near a chart, flattened: bytes, not what
      // is seen. Not into the input's own palette, where each flat block's mean would take
      // the nearest entry, and the coarse levels another colour (Duck: q 0.000292 -> 0.000298
      // for 1 % of its bytes).
      // Nor under --max-gmsd, which resizes the texture afterwards by any ratio. Distances wrap
      // where any of the layout's samplers repeats.
      if (!(settings.palette && !settings.palette_colours.empty()) && o.max_gmsd <= 0)
        atlas::coarsen_gutter(baked, coverage.footprint, ro.role == atlas::RebakeRole::Color, repeats[0], repeats[1]);
      if (settings.palette_when_faithful)
        settings.importance = palette_importance(coverage.footprint, baked.width, baked.height, repeats[0], repeats[1]);
      file.image_bytes[size_t(i)] = io::encode_image(baked, settings);
      out.old_texels += double(source.width) * source.height;
      out.new_texels += double(baked.width) * baked.height;
      TextureReport& t = out.textures.emplace_back();
      t.image = i;
      t.name = img.name;
      t.role = img.uses.empty() ? "other" : io::to_string(img.uses.front().role);
      t.old_size = {source.width, source.height};
      t.new_size = {baked.width, baked.height};
      t.old_bytes = old_bytes.size();
      t.new_bytes = file.image_bytes[size_t(i)].size();  // a draft's; count_texture_costs counts what is written
      if (settings.draft) out.drafts.push_back({i, std::move(baked), std::move(settings)});
      if (progress) progress(bake_stage, ++baked_count, L.images.size());
    }
    out.t_bake += t0.seconds();

    // New UV accessors (the old ones may be shared with primitives outside the layout).
    for (size_t si = 0; si < L.uv_sets.size(); ++si) {
      const io::Primitive& prim = asset.primitives[size_t(L.uv_sets[si].primitive)];
      auto& gp = file.model.meshes[size_t(prim.mesh)].primitives[size_t(prim.primitive)];
      gp.attributes["TEXCOORD_" + std::to_string(L.uv_sets[si].tex_coord)] = io::append_float_accessor(file.model, new_uv[si], TINYGLTF_TYPE_VEC2);
    }
    out.flips += layout_flips;
    out.charts += charts.size();
    out.mesh_failed += mesh_failed;
    out.overlaps_new += overlaps_new;
    out.overlap_fallback_charts += overlapped.size();
    lr.charts = charts.size();
    lr.rigid_charts = P.rigid;
    lr.shared_texel_charts = P.shared_charts;
    lr.packing_units = units.size();
    lr.exact_units = size_t(std::count(unit_exact.begin(), unit_exact.end(), 1));
    lr.pinned_units = pinned_units;
    lr.exact_texels = exact_texels;
    lr.atlas = {packing.width, packing.height};
    // Every unit pinned: no unit took the packing's scale (it is s_max then); they are at 1.
    lr.scale = lr.pinned_units > 0 && lr.pinned_units == units.size() ? 1.0 : packing.scale;
    lr.scale_cap = s_max;
    lr.capped_at_source_density = lr.scale >= 0.999 * s_max;
    lr.packing_efficiency = packing.efficiency;
    lr.gutter = gutter;
    lr.edge_gutter = {budget.pack.edge_x, budget.pack.edge_y};
    lr.gutter_texels = packing.gutter_texels;
    lr.footprint_texels = packing.footprint_texels;
    lr.chart_cost_ratio = choice.cost_ratio;
    lr.flips = layout_flips;
    lr.overlaps_new = overlaps_new;
    lr.overlap_fallback_charts = overlapped.size();
    lr.overlap_fallback_pairs = overlap_fallback_pairs;
    if (cand.outline)
      lr.outline = OutlineReport{outline_kept, outline_failed, outline_kept ? outline_blend / double(outline_kept) : 0.0};
    if (!P.results.empty() && o.optimize) {
      lr.mesh_stage_failed_charts = mesh_failed;
      if (mesh_failed > 1)
        warnings.push_back(cand.name + ": layout " + std::to_string(li) + ": the mesh stage failed on " + std::to_string(mesh_failed) + " charts (kept unreshaped)");
      lr.triangle_stage = P.tri.report(o.triangle);
    }
  }
  return out;
}

// The plain resize a user would do instead (gltf-transform resize, Lanczos-3 in stored
// values): every image of the prepared layouts resized to the size `sizes` gives it.
void resize_images(io::GltfFile& file, const std::vector<std::pair<int, std::array<uint32_t, 2>>>& sizes) {
  for (const auto& [i, size] : sizes) {
    const std::string name = file.path + ": image " + std::to_string(i);
    Image img = io::decode_image(file.image_bytes[size_t(i)], name);
    if (img.width == size[0] && img.height == size[1]) continue;
    Image small = eval::resize_lanczos3(img, size[0], size[1], false);
    file.image_bytes[size_t(i)] = io::encode_image(small, io::encode_settings_of(file.image_bytes[size_t(i)]));
  }
}

// One run of reparam: the input, the layouts found and prepared, and what the stages
// below decide. The stages run in the order reparam() calls them (DESIGN's diagram).
struct Run {
  Run(io::GltfFile& f, engine::Engine& e, const ReparamOptions& opt, const Progress& p)
      : file(f), original(f), engine(e), o(opt), progress(p), asset(io::build_asset(f)), layouts(find_layouts(asset)) {}
  io::GltfFile& file;           // becomes the output
  const io::GltfFile original;  // the input, as loaded
  engine::Engine& engine;
  const ReparamOptions& o;
  const Progress& progress;
  io::Asset asset;
  std::vector<Layout> layouts;
  std::vector<LayoutReport> layout_base;  // per layout: images, driver, UV sets (untouched ones as found)
  std::vector<Prepared> prepared;    // the layouts reparam changes
  json warnings = json::array();
  size_t optimized = 0, infeasible = 0;  // triangles through the triangle stage, those kept at the identity
  double t_triangle = 0, t_score = 0, t_build = 0;  // t_build: every candidate's realize()
  double t_score_far = 0;                           // the part of t_score spent on the far views
  std::unique_ptr<eval::AsWrittenScorer> scorer;  // candidates and the guard: 20 views as written
  std::unique_ptr<eval::AsWrittenScorer> far_scorer;  // the guard's views at a distance (kFarViewPixels)
  std::string score_failure;                      // why eval cannot score the asset
  Realized chosen;                                // the kept candidate, built into `file`
  Candidate chosen_plan;
  // The plans build_curve() chooses among at each cost: the kept one before the wider gutter
  // and the best base plan of another name, each at both gutters when the gutter is
  // automatic, the second-best other, and the +mip-aligned variants (choose_layout).
  std::vector<Candidate> curve_plans;
  ReparamResult result;
};

// The charts of every UV set of layout L (cut at UV seams, vertices welded by position and
// UV), in texels of the W x H driver: each turned counter-clockwise, those of mixed
// orientation kept rigid; then which of them share source texels.
void find_layout_charts(const io::Asset& asset, const Layout& L, Prepared& P, double W, double H) {
  std::vector<Chart>& charts = P.charts;
  auto& welded_of_vertex = P.welded_of_vertex;
  auto& welded_count = P.welded_count;
  welded_of_vertex.resize(L.uv_sets.size()), welded_count.resize(L.uv_sets.size()), P.results.resize(L.uv_sets.size());
  for (size_t si = 0; si < L.uv_sets.size(); ++si) {
    const io::Primitive& prim = asset.primitives[size_t(L.uv_sets[si].primitive)];
    const std::vector<float>& uv = prim.uv_sets[size_t(L.uv_sets[si].tex_coord)].uv;
    Mesh welded = atlas::weld_uv_mesh(prim.positions.data(), uv.data(), prim.vertex_count(), prim.indices.data(),
                                      prim.indices.size());
    welded_count[si] = welded.uv_count();
    welded_of_vertex[si].assign(prim.vertex_count(), UINT32_MAX);
    for (size_t c = 0; c < prim.indices.size(); ++c) welded_of_vertex[si][prim.indices[c]] = welded.uv_triangles[c];
    atlas::Charts found = atlas::find_charts(welded);

    for (atlas::ChartMesh& piece : atlas::split_charts(welded, found)) {
      Chart& ch = charts.emplace_back();
      ch.uv_set = si;
      ch.positions = atlas::chart_surface(welded, piece).positions;
      ch.triangles = std::move(piece.triangles);
      ch.vertices = std::move(piece.uv_vertices);
      ch.local = std::move(piece.corners);
      for (uint32_t w : ch.vertices) ch.uv.push_back(welded.uvs[2 * w] * W), ch.uv.push_back(welded.uvs[2 * w + 1] * H);
      // Orientation: all triangles one way (a mirrored chart is flipped consistently);
      // mixed orientations mean folds or overlaps in UV, kept rigid.
      size_t positive = 0, negative = 0;
      for (size_t t = 0; t < ch.triangles.size(); ++t) {
        double a = signed_area(&ch.uv[2 * ch.local[3 * t]], &ch.uv[2 * ch.local[3 * t + 1]], &ch.uv[2 * ch.local[3 * t + 2]]);
        P.old_used += std::abs(a);
        positive += a > 0, negative += a < 0;
      }
      if (negative > positive)
        for (size_t t = 0; t < ch.triangles.size(); ++t) std::swap(ch.local[3 * t + 1], ch.local[3 * t + 2]);
      ch.rigid = positive > 0 && negative > 0;
      P.rigid += ch.rigid;
    }
  }
  find_shared_texels(P);
}

// The triangle stage over the charts that may be reshaped (rigid charts and charts sharing
// texels keep their shape: optimizing them would be wasted work). With rate control
// (rate_scale > 0), each triangle's bound comes from its loss under the plain resize.
void run_triangle_stage(Run& run, size_t li, const Layout& L, Prepared& P, const std::vector<float>& luminance,
                        double rate_scale) {
  const ReparamOptions& o = run.o;
  const io::Asset& asset = run.asset;
  engine::Engine& engine = run.engine;
  const Progress& progress = run.progress;
  const Image& driver = P.driver;
  const std::vector<Chart>& charts = P.charts;
  auto& tri = P.tri;
  for (size_t si = 0; si < L.uv_sets.size(); ++si) {
    const io::Primitive& prim = asset.primitives[size_t(L.uv_sets[si].primitive)];
    const std::vector<float>& uv = prim.uv_sets[size_t(L.uv_sets[si].tex_coord)].uv;
    std::vector<uint32_t> which;
    for (const Chart& ch : charts)
      if (ch.uv_set == si && !ch.rigid && !ch.shared) which.insert(which.end(), ch.triangles.begin(), ch.triangles.end());
    std::sort(which.begin(), which.end());
    // Kept per triangle (the candidates derive their targets from it).
    if (o.optimize && !o.isometric && !which.empty()) {
      Stopwatch t0;
      perceptual::TriangleViewInput in{prim.positions.data(), prim.vertex_count(), prim.indices.data(),
                                       prim.triangle_count(), uv.data(), driver.width, driver.height};
      perceptual::TriangleStageOptions topt = o.triangle;
      if (rate_scale > 0) {
        // Rate control: each triangle may lose at most a little more than the plain resize
        // to the requested cost would make it lose (its loss at J = sqrt(c) I, measured on
        // its own views), so the optimizer only ever trades texels where the resize would
        // have spent them for nothing.
        const double s0 = rate_scale;
        std::vector<double> g = perceptual::measure_triangles(engine, in, luminance, topt, {s0, 0, 0, s0}, which);
        topt.epsilons.assign(prim.triangle_count(), o.triangle.epsilon);
        for (size_t k = 0; k < which.size(); ++k) {
          topt.epsilons[which[k]] = std::max(o.rate_margin * g[k], o.rate_floor);
          tri.rate_epsilons.push_back(topt.epsilons[which[k]]);
        }
        topt.start_scale = s0;
      }
      if (progress) {
        const std::string stage = "triangles (layout " + std::to_string(li) + ")";
        topt.progress = [&progress, stage](size_t done, size_t total) { progress(stage, done, total); };
      }
      auto results = perceptual::optimize_triangles(engine, in, luminance, topt, which);
      P.results[si].assign(prim.triangle_count(), perceptual::TriangleResult{});  // evaluations 0: not optimized
      for (size_t k = 0; k < results.size(); ++k) {
        const auto& r = results[k];
        tri.optimized += 1;
        tri.evaluations += size_t(r.evaluations);
        tri.feasible += r.feasible;
        if (!r.feasible) tri.infeasible_identity_gmsd.push_back(r.identity_gmsd);
        tri.resolved += r.texels_per_pixel <= 1.0 + 1e-6;
        tri.sampled += !r.complete;
        tri.coarsened += r.identity_lattice > 1;
        tri.lambda_area.push_back(r.lambda1 * r.lambda2);
      }
      for (size_t k = 0; k < results.size(); ++k) P.results[si][which[k]] = std::move(results[k]);
      run.t_triangle += t0.seconds();
    }
  }
}

// What the equal-slope allocation (equal_slope_at) needs of the layout's optimized
// triangles: each triangle's loss at a few uniform shrinks, measured on its own views.
void measure_slope_losses(Run& run, const Layout& L, Prepared& P, const std::vector<float>& luminance,
                          double rate_scale) {
  const ReparamOptions& o = run.o;
  const io::Asset& asset = run.asset;
  engine::Engine& engine = run.engine;
  const Image& driver = P.driver;
  if (o.optimize && o.candidates && rate_scale > 0 && P.tri.optimized > 0) {
    Stopwatch t0;
    perceptual::LossCurves curves;
    curves.scales = kSlopeScales;
    std::vector<std::pair<size_t, uint32_t>> where;  // (UV set, triangle) per allocated triangle
    std::vector<double> area, weight;
    for (size_t si = 0; si < L.uv_sets.size(); ++si) {
      if (P.results[si].empty()) continue;
      const io::Primitive& prim = asset.primitives[size_t(L.uv_sets[si].primitive)];
      const std::vector<float>& uv = prim.uv_sets[size_t(L.uv_sets[si].tex_coord)].uv;
      std::vector<uint32_t> which;
      for (uint32_t t = 0; t < P.results[si].size(); ++t)
        if (P.results[si][t].evaluations > 0) which.push_back(t);
      if (which.empty()) continue;
      perceptual::TriangleViewInput in{prim.positions.data(), prim.vertex_count(), prim.indices.data(),
                                       prim.triangle_count(), uv.data(), driver.width, driver.height};
      // The shrinks' losses (at s = 1 the triangle stage's own measure of the identity).
      std::vector<std::array<double, 4>> jacobians;
      for (double s : curves.scales)
        if (s < 1) jacobians.push_back({s, 0, 0, s});
      std::vector<std::vector<double>> g = perceptual::measure_triangles(engine, in, luminance, o.triangle, jacobians, which);
      g.resize(curves.scales.size());  // the scales are ascending: those at 1 come last, empty
      for (size_t k = 0; k < which.size(); ++k) {
        const perceptual::TriangleResult& r = P.results[si][which[k]];
        where.push_back({si, which[k]});
        area.push_back(std::max(r.texel_area, 1e-9));
        weight.push_back(surface_area(prim, which[k]));
        for (size_t j = 0; j < curves.scales.size(); ++j)
          curves.loss.push_back(curves.scales[j] < 1 ? g[j][k] : r.identity_gmsd);
      }
    }
    P.slope_loss = std::move(curves), P.slope_area = std::move(area), P.slope_weight = std::move(weight);
    P.slope_where = std::move(where);
    run.t_triangle += t0.seconds();
  }
}

// Layout li: its charts, which of them may be reshaped, and the triangle stage's targets
// (with rate control, the losses the equal-slope allocations need, per triangle and per
// packing unit).
void prepare_layout(Run& run, size_t li) {
  const ReparamOptions& o = run.o;
  const io::Asset& asset = run.asset;
  const io::GltfFile& file = run.file;
  const Progress& progress = run.progress;
  json& warnings = run.warnings;
  auto& layout_base = run.layout_base;
  const Layout& L = run.layouts[li];
  LayoutReport lr;
  lr.images = L.images, lr.driver = L.driver;
  for (auto& s : L.uv_sets) {
    const io::Primitive& prim = asset.primitives[size_t(s.primitive)];
    lr.uv_sets.push_back({prim.mesh, prim.primitive, s.tex_coord});
  }
  if (!L.untouched.empty()) {
    lr.untouched = L.untouched;
    warnings.push_back("layout " + std::to_string(li) + " left untouched: " + L.untouched);
    layout_base.push_back(lr);
    return;
  }
  layout_base.push_back(lr);
  run.prepared.emplace_back();
  Prepared& P = run.prepared.back();
  P.index = li;
  const std::string driver_name = file.path + ": image " + std::to_string(L.driver);
  P.driver = io::decode_image(file.image_bytes[size_t(L.driver)], driver_name);
  const Image& driver = P.driver;
  const double W = driver.width, H = driver.height;
  P.W = W, P.H = H;
  // The uniform scale a plain resize to the requested cost applies (rate control's yardstick).
  double rate_scale = 0;
  if (o.optimize && !o.isometric && o.rate_control && o.max_gmsd <= 0) {
    const double c = o.size > 0 ? double(o.size) * o.size * std::min(W, H) / std::max(W, H) / (W * H) : o.cost;
    rate_scale = std::sqrt(std::min(1.0, c));
  }
  std::vector<float> luminance = luminance_plane(driver);

  find_layout_charts(asset, L, P, W, H);
  if (o.isometric) {
    const std::string stage = "flatten (layout " + std::to_string(li) + ")";
    if (progress) progress(stage, 0, 1);
    prepare_isometric(P, o.flatten);
    if (progress) progress(stage, 1, 1);
    for (const std::string& k : P.isometric.kept) warnings.push_back("layout " + std::to_string(li) + " " + k + " (input shape kept)");
  }

  run_triangle_stage(run, li, L, P, luminance, rate_scale);
  measure_slope_losses(run, L, P, luminance, rate_scale);
  // Uniform scales per packing unit (the `unit-scale` candidate).
  if (o.optimize && o.candidates && rate_scale > 0) {
    Stopwatch t0;
    measure_unit_losses(asset, L, P, run.engine, luminance, o.triangle);
    P.requested_share = rate_scale * rate_scale;
    run.t_triangle += t0.seconds();
  }
  run.optimized += P.tri.optimized, run.infeasible += P.tri.optimized - P.tri.feasible;
}

// The candidate layouts (see each): the paper's targets, variants of them, the input's
// charts repacked, per-unit scales; the isometric layout alone for flatten --assign.
std::vector<Candidate> plan_candidates(const Run& run) {
  const ReparamOptions& o = run.o;
  const std::vector<Prepared>& prepared = run.prepared;
  const size_t optimized = run.optimized;
  std::vector<Candidate> plans;
  // Nothing to reshape (every chart rigid or sharing texels): the repack is every candidate.
  const bool reshape = o.optimize && (optimized > 0 || o.max_gmsd > 0);
  if (reshape) plans.push_back({"optimized", true, 0.0});
  if (o.max_gmsd <= 0 && !prepared.empty() && o.candidates && reshape) {
    // The triangle stage's rotations are its least reliable output (a triangle whose loss
    // barely depends on alpha still gets an alpha, and neighbours' disagreeing rotations
    // shear the chart): measured on Fox at half the texels, stretch-only targets score q
    // 0.0029 where the paper's score 0.0090.
    plans.push_back({"stretch-only", true, 0.0, Candidate::Bake::Lanczos, false});
    plans.push_back({"stretch-only-0.5", true, 0.5, Candidate::Bake::Lanczos, false});
    plans.push_back({"floor-0.5", true, 0.5});
    // The same targets with every reshaped chart kept in its input outline: an outline that
    // bulges packs badly, and the user pays for the whole image (demo: 56 % of the image
    // under the reshaped chart against 95 % under the input's).
    plans.push_back({"optimized-outline", true, 0.0, Candidate::Bake::Lanczos, true, true, true});
    plans.push_back({"stretch-only-outline", true, 0.0, Candidate::Bake::Lanczos, false, true, true});
    plans.push_back({"floor-0.5-outline", true, 0.5, Candidate::Bake::Lanczos, true, true, true});
    // Targets that spend the budget where a texel buys the most loss back
    // (perceptual/rate_allocation.h): isotropic, free and in the input's outline, and with
    // the triangle stage's stretch shape (floored at 0.5, unrotated) at the allocated area.
    // Measured at half the texels: the demo q 0.0198 (outline; best other 0.0230), Fox
    // 0.00164 (shaped; best other 0.00203), the truck 0.00657 (outline, least squares;
    // best other 0.00691).
    bool equal_slope = false;
    for (const Prepared& P : prepared) equal_slope |= !P.slope_where.empty();
    if (equal_slope) {
      plans.push_back({"equal-slope", true, 0.0, Candidate::Bake::Lanczos, false, true, false, true});
      plans.push_back({"equal-slope-outline", true, 0.0, Candidate::Bake::Lanczos, false, true, true, true});
      plans.push_back({"equal-slope-shaped", true, 0.5, Candidate::Bake::Lanczos, false, true, false, true});
    }
  }
  if (!reshape || (o.max_gmsd <= 0 && o.candidates)) plans.push_back({"repack", false, 1.0});
  // The input's charts unreshaped, each packing unit at its own scale: where the signal
  // sits in a few units (Duck's eye), the smooth ones give their texels to it.
  bool unit_scales = false;
  for (const Prepared& P : prepared) unit_scales |= unit_scales_differ(P, P.requested_share);
  if (o.max_gmsd <= 0 && o.candidates && unit_scales) {
    Candidate c{"unit-scale", false, 1.0};
    c.unit_scale = true;
    plans.push_back(c);
  }
  if (o.isometric) {  // flatten --assign: that layout alone
    plans.clear();
    Candidate iso{"isometric", true, 0.0};
    iso.isometric = true;
    plans.push_back(iso);
  }
  return plans;
}

// Candidates and the guard are scored as written against the input, its layout and 20
// views set up once. When eval cannot score the asset, reparam keeps the paper's layout
// and says so.
void set_up_scoring(Run& run) {
  const ReparamOptions& o = run.o;
  json& warnings = run.warnings;
  std::string& score_failure = run.score_failure;
  std::unique_ptr<eval::AsWrittenScorer>& scorer = run.scorer;
  const io::GltfFile& original = run.original;
  engine::Engine& engine = run.engine;
  double& t_score = run.t_score;
  Stopwatch t0;
  eval::EvalOptions score_options;
  score_options.artifacts = false;
  score_options.resolution = o.score_resolution, score_options.filter = o.score_filter;
  score_options.shading = o.score_shading;
  score_options.noise_floor = false;  // eval's 7 extra renders; the candidates are compared as measured
  try {
    scorer = std::make_unique<eval::AsWrittenScorer>(original, engine, score_options);
    // The views draw one image's primitives (eval's driving texture). Where reparam leaves
    // that image's layout as it is (TextureTransformTest's 'UV.png', sampled through
    // KHR_texture_transform), they are drawn with the driver of the re-parameterized layout
    // that the most triangles sample instead, so that q sees a layout reparam changes.
    const int seen = scorer->driving_image();
    bool seen_untouched = false;
    int driver = -1;
    size_t most = 0;
    for (const Layout& L : run.layouts) {
      if (std::find(L.images.begin(), L.images.end(), seen) != L.images.end()) seen_untouched = !L.untouched.empty();
      if (!L.untouched.empty()) continue;
      size_t triangles = 0;
      for (const UvSet& u : L.uv_sets) triangles += run.asset.primitives[size_t(u.primitive)].triangle_count();
      if (triangles > most) most = triangles, driver = L.driver;
    }
    if (seen_untouched && driver >= 0) {
      score_options.driving_image = driver;
      scorer = std::make_unique<eval::AsWrittenScorer>(original, engine, score_options);
      warnings.push_back("scoring: the views draw the primitives of image " + std::to_string(driver) +
                         " (re-parameterized), not those of image " + std::to_string(seen) + ", which reparam leaves as it is");
    }
    // The same views from afar (the asset filling kFarViewPixels): what the guard says about
    // coarse mip levels, which views that resolve every texel never sample.
    if (o.score_resolution == 0 || o.score_resolution > kFarViewPixels) {
      eval::EvalOptions far = score_options;
      far.resolution = kFarViewPixels;
      far.noise_floor = true;  // at this size sampling phase alone moves q by up to 15 % (the truck: 0.0019 of 0.0124)
      const Stopwatch t1;
      try {
        run.far_scorer = std::make_unique<eval::AsWrittenScorer>(original, engine, far);
        run.t_score_far += t1.seconds();
      } catch (const InputError& e) {  // the near views stand: only what they cannot tell goes unsaid
        warnings.push_back(std::string("scoring: not scored from afar (") + e.what() + ")");
      }
    }
    run.result.scoring = ReparamResult::Scoring{scorer->resolution(), o.score_filter, scorer->shading()};
    if (!scorer->shading_warning().empty()) warnings.push_back("scoring: " + scorer->shading_warning());
  } catch (const InputError& e) {
    // eval cannot score this asset (e.g. no UV area to frame): keep the paper's layout,
    // skip the guard, and say so.
    score_failure = e.what();
    warnings.push_back("candidates and the resize guard skipped: eval cannot score this asset (" + score_failure + ")");
  }
  t_score += t0.seconds();
}

// Scores a layout as written over eval's views: a stage of its own on the progress display.
eval::Scored score(Run& run, const io::GltfFile& f, const std::string& name) {
  Stopwatch t0;
  if (run.progress) run.progress("score (" + name + ")", 0, 1);
  const eval::Scored scored = run.scorer->score(f);
  if (run.progress) run.progress("score (" + name + ")", 1, 1);
  run.t_score += t0.seconds();
  return scored;
}

// The same from afar (Run::far_scorer); -1 without one.
double score_far(Run& run, const io::GltfFile& f) {
  if (!run.far_scorer) return -1;
  Stopwatch t0;
  const double q = run.far_scorer->score(f).q;
  run.t_score += t0.seconds(), run.t_score_far += t0.seconds();
  return q;
}

// What building a candidate showed, for the variants built from it.
struct Considered {
  size_t unreshaped = 0;  // Realized::unreshaped_units
  size_t pinned = 0;      // Realized::pinned_units
};

// Builds a candidate into a copy of the input, scores it, and keeps it (in run.file) when
// it is the first or scores better.
Considered consider_candidate(Run& run, const Candidate& c) {
  io::GltfFile f = run.original;
  const Stopwatch t0;
  Realized r = realize(run.asset, run.layouts, run.prepared, run.layout_base, f, run.engine, run.o, c, run.progress,
                       run.warnings);
  run.t_build += t0.seconds();
  const Stopwatch t1;
  if (run.scorer && r.overlaps_new == 0) r.q = score(run, f, r.name).q;
  run.result.candidates.push_back({r.name, r.old_texels > 0 ? r.new_texels / r.old_texels : 1.0, r.q, r.overlaps_new,
                                   r.t_mesh, r.t_pack, r.t_bake, t1.seconds()});
  const Considered seen{r.unreshaped_units, r.pinned_units};
  // New UV overlaps disqualify a layout whatever its score: never written.
  if (r.overlaps_new > 0) return seen;
  const bool have = !run.chosen.name.empty();
  if (!have || (r.q >= 0 && r.q < run.chosen.q)) run.chosen = std::move(r), run.file = std::move(f), run.chosen_plan = c;
  return seen;
}

// Every plan built and scored, the best kept; then the kept layout with the least-squares
// bake and with wider gutters, each kept only when it scores better.
void choose_layout(Run& run, const std::vector<Candidate>& plans) {
  const ReparamOptions& o = run.o;
  const auto& scorer = run.scorer;
  const Candidate& chosen_plan = run.chosen_plan;
  auto consider = [&run](const Candidate& c) { return consider_candidate(run, c); };
  // The base plans' scores, for the runner-up below.
  std::vector<std::pair<double, size_t>> base_scores;
  std::vector<size_t> copies_of(plans.size(), 0);  // units each base plan copies
  for (size_t i = 0; i < plans.size(); ++i) {
    copies_of[i] = consider(plans[i]).unreshaped;
    const CandidateScore& scored = run.result.candidates.back();
    if (scored.q >= 0 && scored.overlaps_new == 0) base_scores.push_back({scored.q, i});
  }
  std::sort(base_scores.begin(), base_scores.end());  // best first, for the variants below
  if (!run.prepared.empty() && run.chosen.name.empty())
    throw InputError(run.file.path, "every layout built has triangles overlapping in UV that did not in the input "
                                    "(see overlaps_new); nothing written");
  // Below half the texels, those of the two best base plans that allocate texels
  // (equal-slope, unit-scale) once more with their allocation made for half the texels and
  // scaled into the budget whole: the allocation made at a small budget starves the middle
  // triangles for the detailed ones, which the views then see through coarse mip levels anyway. Measured
  // (the half's shapes scaled down): the demo's equal-slope-outline at a fifth of its texels
  // scores q 0.0467 against 0.0589 allocated there, at three tenths 0.0311 against 0.0361
  // (at four tenths 0.0238 against 0.0225: kept only when it scores better); Duck's
  // unit-scale at a tenth 0.00107 against 0.00134.
  if (scorer && o.max_gmsd <= 0 && o.candidates) {
    bool below_half = !run.prepared.empty();
    for (const Prepared& P : run.prepared) below_half &= P.requested_share < kHalfShare * (1 - 1e-9);
    for (size_t k = 0; below_half && k < base_scores.size() && k < 2; ++k) {
      Candidate c = plans[base_scores[k].second];
      if (!c.equal_slope && !c.unit_scale) continue;
      c.allocation_share = kHalfShare, c.name += "+half-allocation";
      consider(c);
    }
  }
  const std::string kept_base = chosen_plan.name;  // the plan the variants below start from
  // The kept layout once more with the least-squares re-bake (the texels whose bilinear
  // reconstruction is closest to the source over the surface), with the unreshaped charts'
  // texels copied and with them solved too: a copy at a fractional scale can blur edges a
  // fit keeps (MultiUVTest at half the texels: q 0.0040 copied, 0.0020 solved). Each is
  // kept only if it scores better. Where no unit keeps its shape (the demo's and Fox's kept
  // layouts reshape every chart) there is nothing to copy: the second is the first again.
  if (scorer && o.least_squares_bake && o.max_gmsd <= 0) {
    const Candidate kept = chosen_plan;
    size_t unreshaped = 0;
    for (bool exact : {true, false}) {
      if (!exact && (!o.exact_texels || unreshaped == 0)) break;  // the same as the first
      Candidate c = kept;
      c.name += exact ? "+least-squares" : "+least-squares-resampled";
      c.bake = Candidate::Bake::LeastSquares, c.exact = exact;
      unreshaped = consider(c).unreshaped;
    }
  }
  // The kept layout once more with gutters a mip level cleaner. Which costs less on screen,
  // the texels a wider gutter takes from the charts or the bleeding between charts at the
  // coarse mip levels that views at grazing angles sample, depends on the asset: measured
  // at half the texels, the Duck's repack scores q 0.000675 at 16 texels against 0.000779
  // at 8 (the resize 0.000692), while Fox loses at 8 what it gains at 16.
  // Built for the kept layout and for the best other plan: two plans that score alike at
  // the default gutter need not score alike at the wider one (Duck: `unit-scale` and
  // `repack` 0.000707 and 0.000779 at 8 texels, 0.000710 and 0.000675 at 16).
  const bool widen = scorer && o.max_gmsd <= 0 && o.gutter == ReparamOptions::kAutoGutter && o.candidates;
  std::vector<Candidate> others;  // the best two base plans of other names, best first
  size_t other_copies = 0;        // units the best of them copies
  for (const auto& [q, i] : base_scores)
    if (plans[i].name != kept_base && others.size() < 2) {
      if (others.empty()) other_copies = copies_of[i];
      others.push_back(plans[i]);
    }
  std::vector<Candidate> pair = {chosen_plan};
  if (!others.empty()) pair.push_back(others[0]);
  // The curve's plans (build_curve): this pair at both gutters, and the second-best other
  // plan at the default gutter. The plan that serves the low costs best is often not the
  // best at `--cost`, and which of two close plans ranks second there is a matter of the BO
  // seed (the truck: `unit-scale` at seed 1, `stretch-only` at seed 2, its ratio 0.847
  // against 0.874), so the curve takes both.
  run.curve_plans = pair;
  for (Candidate c : pair) {
    if (!widen) break;
    c.name += "+wide-gutter", c.wide_gutter = true;
    consider(c);
    run.curve_plans.push_back(c);
  }
  if (others.size() > 1) run.curve_plans.push_back(others[1]);
  // The kept layout (whichever gutter won) and the best other plan once more with the mip
  // chain kept whole (Candidate::mip_aligned), where they copy units (a layout that copies
  // nothing has no phase to keep). Whether that pays for the texels it costs (sides
  // rounded, copies placed on every A-th texel) depends on the asset and its arrangement,
  // so each is kept only when it scores better. The kept plan is also tried with sides
  // clean one level deeper (multiples of 2A). Measured at half the texels (q, the resize's
  // at 362 x 362 0.00069): Duck's `unit-scale+least-squares` 0.00074 unaligned, 0.00060
  // at A, 0.00037 at 2A; `bench quality` ratios with the A variants alone: Duck 0.941 ->
  // 0.516, MultiUVTest 0.774 -> 0.743 (with both: see docs/DEVELOPERS.md).
  // Not under --size N (the sides would round up past the size asked for); under --pot the
  // sides are powers of two already, so only the copies' phase is varied; a plan whose
  // gutter allows no alignment (A = 1) is not varied at all. The copies stay at the
  // source's density (Candidate::pin_copies), and where that pins any the variant is built
  // with one scale too (`-one-scale`): Duck at half the texels,
  // `unit-scale+least-squares+mip-aligned` q 0.000601 with every unit at scale 0.961 (the
  // copies resampled), 0.000281 with the copies at 1 and the rest at 0.937 (the resize
  // 0.00066 at that atlas's shape); at 0.4 of the texels `unit-scale+wide-gutter+mip-aligned`
  // 0.000578 -> 0.000171.
  auto with_alignment = [&](Candidate c, uint32_t depth) -> std::optional<Candidate> {
    c.name += depth == 1 ? "+mip-aligned" : "+mip-aligned-deep", c.mip_aligned = true, c.mip_depth = depth;
    c.pin_copies = true;
    for (const Prepared& P : run.prepared)
      if (budget_options(o, c, P.W, P.H).side_multiple > 1) return c;
    return std::nullopt;
  };
  // The kept plan is aligned at both gutters: which gutter is better aligned is not the one
  // that was better unaligned. A wider gutter's power of two keeps the copies' chain whole
  // one level deeper, and that can outweigh the texels it costs. Duck at half the texels:
  // unaligned, `unit-scale+least-squares` 0.000632 at 8 texels against 0.000655 at 16;
  // aligned (`-deep`), 0.000346 at 8 against 0.000170 at 16, which also beats the resize
  // from afar (0.00045 against 0.00096; 0.00114 at 8) and passes the three.js check in every
  // view (at 8 it failed three, docs/DEVELOPERS.md "The real-client check").
  std::vector<Candidate> kept_plans = {run.chosen_plan};
  if (widen) {
    Candidate twin = run.chosen_plan;
    const std::string suffix = "+wide-gutter";
    if (twin.wide_gutter) {
      twin.wide_gutter = false;
      if (twin.name.size() >= suffix.size() && twin.name.compare(twin.name.size() - suffix.size(), suffix.size(), suffix) == 0)
        twin.name.resize(twin.name.size() - suffix.size());
    } else {
      twin.wide_gutter = true, twin.name += suffix;
    }
    kept_plans.push_back(twin);
  }
  if (scorer && o.max_gmsd <= 0 && o.size == 0 && o.candidates) {
    std::vector<Candidate> aligned;
    if (run.chosen.unreshaped_units > 0)
      for (const Candidate& kept : kept_plans)
        for (uint32_t depth : {1u, 2u}) {
          if (depth == 2 && o.power_of_two) break;
          if (auto c = with_alignment(kept, depth)) aligned.push_back(*c);
        }
    if (!others.empty() && other_copies > 0)
      if (auto c = with_alignment(others[0], 1)) aligned.push_back(*c);
    for (const Candidate& c : aligned) {
      const Considered seen = consider(c);
      run.curve_plans.push_back(c);
      if (seen.pinned == 0) continue;  // nothing pinned: it was built with one scale already
      Candidate one = c;
      one.name += "-one-scale", one.pin_copies = false;
      consider(one);
      run.curve_plans.push_back(one);
    }
  }
}

// The kept candidate's drafted images encoded for good, as the input was (the same texels:
// what was scored is what is written).
void finish_encoding(Run& run) {
  for (auto& d : run.chosen.drafts) {
    d.settings.draft = false;
    run.file.image_bytes[size_t(d.image)] = io::encode_image(d.texels, d.settings);
  }
  run.chosen.drafts.clear();
}

// Reparam's own q-c curve (bench quality, demo): at each of o.curve_costs the best on
// screen of the layouts reparam chose among at the requested cost (Run::curve_plans: the
// kept one and the best other at both gutters, the second-best other at the default
// one, the +mip-aligned variants), each with its shapes as they are, built into that
// budget and scored as written.
// Which plan and which gutter serve a budget best depends on the budget: the plan kept at
// half of Duck's texels (`repack+wide-gutter`) scores q 0.00179 at a tenth,
// `unit-scale+least-squares` 0.00107, the resize 0.00155. The shapes stay those of the
// requested cost: the equal-slope allocation made afresh at each budget serves the demo
// worse below half its texels (q 0.0589 against 0.0467 at a fifth) than the half's layout
// scaled down (the `+half-allocation` plans reparam builds below half the texels).
void build_curve(Run& run) {
  const ReparamOptions& o = run.o;
  json ignored = json::array();  // the curve's layouts warn as the kept one did
  std::vector<ReparamResult::CurvePoint> curve;
  for (double c : o.curve_costs) {
    ReparamOptions at = o;
    at.cost = c, at.size = 0;
    std::optional<ReparamResult::CurvePoint> best;
    for (const Candidate& plan : run.curve_plans) {
      io::GltfFile f = run.original;
      const Realized r = realize(run.asset, run.layouts, run.prepared, run.layout_base, f, run.engine, at, plan, {}, ignored);
      if (r.overlaps_new > 0) continue;  // never written, so not on the curve
      char name[160];
      std::snprintf(name, sizeof name, "curve at c_r %.2f: %s", c, plan.name.c_str());
      const eval::Scored scored = score(run, f, name);
      if (!best || scored.q < best->q) best = ReparamResult::CurvePoint{scored.c_r, scored.q, plan.name};
    }
    if (best) curve.push_back(*best);
    else run.warnings.push_back("curve: every plan built at c_r " + std::to_string(c) + " has new UV overlaps");
  }
  run.result.curve = std::move(curve);
}

// The guard: the same texels spent on a plain resize of the input (Lanczos-3, what users'
// tools do). Whichever looks better on screen is written; --force-reparam skips this.
void guard_against_resize(Run& run) {
  const io::GltfFile& original = run.original;
  io::GltfFile& file = run.file;
  Realized& chosen = run.chosen;
  std::string& chosen_by = run.result.chosen;
  json& warnings = run.warnings;
  double& t_score = run.t_score;
  // The resize at the same texels at the image's own aspect ratio (a user's resize keeps the
  // shape even where the packer chose another one), never more texels than reparam's image
  // (so never over the budget either), sides multiples of `m` (whole blocks with
  // --block-align).
  auto resize_sizes = [&](bool aligned) {
    std::vector<std::pair<int, std::array<uint32_t, 2>>> sizes;
    for (const auto& t : chosen.textures) {
      const double w0 = t.old_size[0], h0 = t.old_size[1];
      const double texels = double(t.new_size[0]) * double(t.new_size[1]);
      uint32_t m = std::max(1u, run.o.block);
      if (aligned)
        for (const LayoutReport& l : chosen.layouts)
          if (std::find(l.images.begin(), l.images.end(), t.image) != l.images.end()) m = std::max(m, l.side_multiple);
      uint32_t w = std::max(m, uint32_t(std::lround(std::sqrt(texels * w0 / h0) / m)) * m);
      if (aligned && double(w) * m > texels) w = m;
      const uint32_t h = std::max(m, uint32_t(std::floor(texels / w)) / m * m);
      sizes.push_back({t.image, {w, h}});
    }
    return sizes;
  };
  // Two resizes, the better one kept: at the nearest size, and with sides multiples of what
  // reparam's image's are (the gutter's power of two), whose mip chain halves exactly as
  // deep as reparam's does. An odd side's chain drifts against level 0 (eval's as a
  // driver's may), and that, not the texels, can decide q: Duck resized to 359 x 359 scores
  // 0.00089, to 352 x 352 0.00068, to 360 x 360 0.00065. The baseline is the resize a user
  // who picks a sensible size gets, not one that a rounding handicaps.
  Guard& guard = run.result.guard;
  io::GltfFile resized = original;
  double q_resize = -1;
  std::vector<std::vector<std::pair<int, std::array<uint32_t, 2>>>> tried;
  for (bool aligned : {false, true}) {
    const auto sizes = resize_sizes(aligned);
    if (std::find(tried.begin(), tried.end(), sizes) != tried.end()) continue;
    tried.push_back(sizes);
    Stopwatch t0;
    io::GltfFile f = original;
    resize_images(f, sizes);
    t_score += t0.seconds();  // the resize; score() counts itself
    const double q = score(run, f, aligned ? "the plain resize, sides aligned" : "the plain resize").q;
    if (q_resize < 0 || q < q_resize) q_resize = q, resized = std::move(f), guard.resize_aligned = aligned;
  }
  guard.ran = true, guard.q_reparam = chosen.q, guard.q_resize = q_resize;
  // From afar, the two files only (every candidate too would cost Fox's run 7 %).
  if (run.far_scorer)
    guard.far = Guard::Far{kFarViewPixels, score_far(run, file), score_far(run, resized), run.far_scorer->resolution().noise_floor};
  // The views draw one image's primitives (a re-parameterized layout's: set_up_scoring),
  // with the maps that share its layout (lit shading); a re-baked image of another layout
  // changes unseen.
  const int seen = run.scorer->driving_image();
  std::vector<int> rendered;
  for (const auto& l : chosen.layouts)
    if (std::find(l.images.begin(), l.images.end(), seen) != l.images.end()) rendered.insert(rendered.end(), l.images.begin(), l.images.end());
  for (const auto& t : chosen.textures)
    if (std::find(rendered.begin(), rendered.end(), t.image) == rendered.end()) guard.unseen.push_back(t.name);
  if (!guard.unseen.empty()) {
    std::string names;
    for (const auto& n : guard.unseen) names += (names.empty() ? "'" : ", '") + n + "'";
    warnings.push_back("the scoring views render only the layout of image " + std::to_string(seen) +
                       "; q does not see the re-baked " + names + " (neither reparam's nor the resize's)");
  }
  // A layout that was not scored (q < 0) never wins against one that was.
  if (!(chosen.q >= 0 && chosen.q < q_resize)) {
    chosen_by = "resize";
    file = std::move(resized);
    for (auto& t : chosen.textures) t.new_bytes = file.image_bytes[size_t(t.image)].size();
    std::string q = "(q " + std::to_string(q_resize) + " vs " + std::to_string(chosen.q);
    if (guard.far) q += "; from afar " + std::to_string(guard.far->q_resize) + " vs " + std::to_string(guard.far->q_reparam);
    q += ")";
    warnings.push_back(q_resize == chosen.q ? "the plain resize to the same texels ties with reparam's layout " + q + ": wrote the resize"
                                              : "the plain resize to the same texels looks better " + q + ": wrote the resize");
  }
  guard.chosen = chosen_by;
  // The choice is made up close (q); from afar reparam's layout may still lose: said, where
  // by more than the far views' noise floor (less is sampling phase, a tie).
  if (chosen_by == "reparam" && guard.far && guard.far->q_reparam > guard.far->q_resize + guard.far->noise_floor) {
    char text[260];
    std::snprintf(text, sizeof text,
                  "from afar (the asset filling %u-pixel views: coarse mip levels) the plain resize looks better: q %.3g vs %.3g "
                  "for reparam's layout, which is kept for what it gains up close (q %.3g vs %.3g)",
                  guard.far->resolution, guard.far->q_resize, guard.far->q_reparam, guard.q_reparam, guard.q_resize);
    warnings.push_back(text);
  }
}

// --max-gmsd: the layout made at the source density, evaluated on a cost grid (eval's
// protocol), and its re-baked textures area-filtered down to the cheapest point of that
// q-c curve that meets the bound.
void size_to_max_gmsd(Run& run) {
  const ReparamOptions& o = run.o;
  const io::GltfFile& original = run.original;
  io::GltfFile& file = run.file;
  Realized& chosen = run.chosen;
  engine::Engine& engine = run.engine;
  const Progress& progress = run.progress;
  json& warnings = run.warnings;
  Stopwatch t0;
  eval::EvalOptions eo;
  eo.resolution = o.score_resolution, eo.filter = o.score_filter, eo.shading = o.score_shading;
  eo.noise_floor = false;
  eo.artifacts = false;
  eo.cost_grid = {0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0};
  const eval::EvalResult ev = eval::evaluate(original, {{"reparam", &file}}, engine, eo, nullptr,
                                             progress ? eval::Progress(progress) : eval::Progress());
  const eval::LayoutResult& layout = ev.layouts[1];
  // eval's sizes are image texels relative to the input's image: the point's width is the
  // size to write, whatever the packing made of the written image.
  const double full_w = layout.as_written->width;
  double ratio = 1, chosen_q = layout.curve.back().q, chosen_c = 1;
  bool met = false;
  for (const auto& point : layout.curve)
    if (point.q <= o.max_gmsd) {
      ratio = std::min(1.0, point.width / full_w);
      chosen_q = point.q, chosen_c = point.c_r;
      met = true;
      break;
    }
  if (!met) warnings.push_back("no size meets --max-gmsd " + std::to_string(o.max_gmsd) + "; kept the source density");
  chosen.new_texels = 0;
  for (auto& t : chosen.textures) {
    const int i = t.image;
    Image img = io::decode_image(file.image_bytes[size_t(i)], file.path);
    const uint32_t w = std::max(1u, uint32_t(std::lround(img.width * ratio)));
    const uint32_t h = std::max(1u, uint32_t(std::lround(img.height * ratio)));
    if (w != img.width || h != img.height) {
      file.image_bytes[size_t(i)] =
          io::encode_image(eval::resize_area(img, w, h), io::encode_settings_of(original.image_bytes[size_t(i)]));
    }
    t.new_size = {w, h};
    t.new_bytes = file.image_bytes[size_t(i)].size();
    chosen.new_texels += double(w) * h;
  }
  run.result.max_gmsd = MaxGmsd{o.max_gmsd, met, chosen_c, chosen_q, ratio};
  run.result.stages.max_gmsd_eval = t0.seconds();
}

// What each texture costs as written (texels, encoded bytes, VRAM) against the input's,
// and against the input resized (Lanczos-3) to the same size and encoded the same way:
// the bytes a user's resize would have cost for those texels.
void count_texture_costs(Run& run) {
  const io::GltfFile& original = run.original;
  const io::GltfFile& file = run.file;
  Stopwatch t0;
  ReparamResult::TextureTotals& totals = run.result.texture_totals;
  TextureCost &old_total = totals.old_cost, &new_total = totals.new_cost;
  uint64_t &old_bytes = totals.old_bytes, &new_bytes = totals.new_bytes, &resize_bytes = totals.resize_bytes;
  for (auto& t : run.chosen.textures) {
    const size_t i = size_t(t.image);
    const std::vector<uint8_t>& before = original.image_bytes[i];
    const std::vector<uint8_t>& after = file.image_bytes[i];
    const io::ImageHeader hb = io::read_image_header(before, file.path), ha = io::read_image_header(after, file.path);
    const io::EncodeSettings settings = io::encode_settings_of(before);
    const Image source = io::decode_image(before, file.path);
    const Image resized = ha.width == hb.width && ha.height == hb.height
                              ? source
                              : eval::resize_lanczos3(source, ha.width, ha.height, false);
    const size_t resize = io::encode_image(resized, settings).size();
    const TextureCost cb = texture_cost(hb.width, hb.height), ca = texture_cost(ha.width, ha.height);
    t.new_size = {ha.width, ha.height};  // the resize's when the guard wrote it
    t.new_bytes = after.size();
    t.encoding = io::describe(settings);
    t.written = io::describe_encoded(after);
    t.old_cost = cb, t.new_cost = ca;
    t.resize_bytes = resize;
    t.bytes_ratio = double(after.size()) / double(std::max<size_t>(1, before.size()));
    t.bytes_vs_resize = double(after.size()) / double(std::max<size_t>(1, resize));
    old_total.texels += cb.texels, old_total.vram_rgba8 += cb.vram_rgba8, old_total.vram_bc7 += cb.vram_bc7;
    new_total.texels += ca.texels, new_total.vram_rgba8 += ca.vram_rgba8, new_total.vram_bc7 += ca.vram_bc7;
    old_bytes += before.size(), new_bytes += after.size(), resize_bytes += resize;
  }
  run.result.stages.texture_costs = t0.seconds();
}

}  // namespace

ReparamResult reparam(io::GltfFile& file, engine::Engine& engine, const ReparamOptions& o, const Progress& progress,
                      io::GltfFile* layout_out) {
  const Stopwatch t_start;
  Run run(file, engine, o, progress);
  ReparamResult& result = run.result;
  result.device = engine.device();
  for (size_t li = 0; li < run.layouts.size(); ++li) prepare_layout(run, li);
  const std::vector<Candidate> plans = plan_candidates(run);
  const bool scoring =
      !run.prepared.empty() && (plans.size() > 1 || (o.max_gmsd <= 0 && (o.guard || o.least_squares_bake)));
  if (scoring) set_up_scoring(run);
  choose_layout(run, plans);
  finish_encoding(run);
  if (!o.curve_costs.empty() && run.scorer) build_curve(run);
  if (layout_out) *layout_out = file;
  result.chosen = run.prepared.empty() ? "untouched" : "reparam";
  result.guard.skipped = run.score_failure;
  if (o.guard && o.max_gmsd <= 0 && run.scorer) guard_against_resize(run);
  if (o.max_gmsd > 0 && !run.chosen.textures.empty()) size_to_max_gmsd(run);
  count_texture_costs(run);
  // Nothing the replacement left unreferenced is written (the old UV accessors, their
  // bufferViews, the old image bytes); what the input itself left unused stays.
  result.pruned = io::prune_replaced(file, run.original.model);
  if (!result.pruned.skipped.empty())
    run.warnings.push_back("unreferenced accessors and bufferViews kept: " + result.pruned.skipped);

  const Realized& chosen = run.chosen;
  const bool resized = result.chosen == "resize";
  result.stages.triangle_stage = run.t_triangle;
  result.stages.mesh_stage = chosen.t_mesh;
  result.stages.pack = chosen.t_pack;
  result.stages.rebake = chosen.t_bake;
  result.stages.candidates_and_guard = run.t_score;
  result.stages.score_far = run.t_score_far;
  result.stages.candidates_built = run.t_build;
  result.layout = chosen.name;
  if (resized) result.q = result.guard.q_resize;
  else if (chosen.q >= 0) result.q = chosen.q;
  result.layouts = chosen.layouts;
  result.textures = chosen.textures;
  result.cost_ratio = chosen.old_texels > 0 ? chosen.new_texels / chosen.old_texels : 1.0;
  result.flips = resized ? 0 : chosen.flips;
  result.overlaps_new = resized ? 0 : chosen.overlaps_new;  // always 0 in a written file
  result.overlap_fallback_charts = resized ? 0 : chosen.overlap_fallback_charts;
  result.charts = chosen.charts;
  result.triangles_optimized = run.optimized;
  result.triangles_infeasible = run.infeasible;
  for (const auto& w : run.warnings) result.warnings.push_back(w.get<std::string>());
  result.seconds = t_start.seconds();
  return result;
}

}  // namespace uvpress::pipeline
