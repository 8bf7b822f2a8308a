// Re-baking a texture into new UVs (rebake.h). How:
//
// For every texel of the new image, the triangle that owns it is found among the new-UV
// triangles that overlap the texel's square (conservative rasterization): the one whose
// distance to the texel centre is smallest (0 when the centre is inside), ties to the
// lowest triangle index (meshes in order). The texel's footprint is mapped to the old
// texture by that triangle's affine map (barycentrics), and the old texture is sampled:
//
// Filter: box-filtered supersampling of bilinear samples. The new texel's square maps to a
// parallelogram in old texels with edges J e_x and J e_y (J = d old texel / d new texel);
// n_x = ceil(|J e_x|) by n_y = ceil(|J e_y|) samples (each at most max_samples) on a
// regular grid inside the new texel, each bilinear, averaged with equal weights. For an
// integer downscale this is the exact area (box) filter (a 2x2 reduction averages four
// texels exactly); at 1:1 or upscaling it is plain bilinear, so an identity re-bake is
// exact. Sample points are clamped into the owning triangle, so nothing is read from
// outside the source chart (the source's own gutter never bleeds in).
//
// Colour (sRGB-encoded) textures are filtered in linear light (decoded exactly through a
// table, re-encoded with the sRGB formula): averaging encoded values darkens edges and
// fine detail. Textures with alpha are filtered premultiplied (colour weighted by alpha,
// then divided), so invisible texels do not tint visible ones; alpha itself is filtered
// linearly and kept. Data textures (metallic-roughness, occlusion, ...) are filtered as
// stored.
//
// Normal maps (tangent-space, glTF: +X right, +Y up in the image, i.e. toward -v): the
// filtered vector n = 2 v - 1 has its xy rotated by the orthogonal polar factor of the
// triangle's Jacobian old -> new, taken in texel units and conjugated by diag(1, -1) for
// the v-down convention, then renormalized. This assumes square texels are square on the
// surface (the true tangent frame would need 3-D positions); for conformal layouts it is
// exact. When the Jacobian mirrors (det < 0) the factor is a reflection, which keeps xy
// correct relative to the new u/v axes (tangents' handedness is then the caller's).
//
// Gutter: texels covered by no triangle are filled for the mip chain (atlas/gutter_fill.h):
// a ring of the nearest chart texel's value, then each chart's colour extended through
// every mip level, so bilinear and mip sampling at chart borders sees chart colours,
// never background or (down to the level the gutter's width allows) a neighbour's.
#include "atlas/rebake.h"

#include "atlas/pack.h"
#include "core/stopwatch.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace uvpress::atlas {

float srgb_to_linear(float v) {
  v = std::clamp(v, 0.0f, 1.0f);
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

float linear_to_srgb(float v) {
  v = std::clamp(v, 0.0f, 1.0f);
  return v <= 0.0031308f ? v * 12.92f : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

namespace {

// Exact for 8- and 16-bit values (k/255 = 257k/65535).
const std::vector<float>& srgb_table() {
  static const std::vector<float> table = [] {
    std::vector<float> t(65536);
    for (int i = 0; i < 65536; ++i) t[i] = srgb_to_linear(float(double(i) / 65535.0));
    return t;
  }();
  return table;
}

// linear -> sRGB by linear interpolation in a 16K table: error < 2e-6 (below a 16-bit step).
constexpr int kEncodeSteps = 16384;
const std::vector<float>& encode_table() {
  static const std::vector<float> table = [] {
    std::vector<float> t(kEncodeSteps + 2);
    for (int i = 0; i <= kEncodeSteps + 1; ++i)
      t[i] = linear_to_srgb(float(std::min(1.0, double(i) / kEncodeSteps)));
    return t;
  }();
  return table;
}

inline float encode_with(const float* table, float v) {
  v = std::clamp(v, 0.0f, 1.0f) * kEncodeSteps;
  const int i = int(v);
  const float f = v - float(i);
  return table[i] + f * (table[i + 1] - table[i]);
}

using Tri = engine::RebakeTriangle;

// Orthogonal polar factor of a 2x2 matrix (rotation, or reflection when det < 0).
void polar_factor(const double M[2][2], float Q[2][2]) {
  const double a = M[0][0], b = M[0][1], c = M[1][0], d = M[1][1];
  if (a * d - b * c >= 0) {
    const double th = std::atan2(c - b, a + d);
    Q[0][0] = float(std::cos(th)), Q[0][1] = float(-std::sin(th));
    Q[1][0] = float(std::sin(th)), Q[1][1] = float(std::cos(th));
  } else {
    const double ph = std::atan2(c + b, a - d);
    Q[0][0] = float(std::cos(ph)), Q[0][1] = float(std::sin(ph));
    Q[1][0] = float(std::sin(ph)), Q[1][1] = float(-std::cos(ph));
  }
}

}  // namespace

float srgb_decode_fast(float v) { return srgb_table()[size_t(std::clamp(v, 0.0f, 1.0f) * 65535.0f + 0.5f)]; }

float srgb_encode_fast(float v) { return encode_with(encode_table().data(), v); }

RebakePlan plan_rebake(const Image& source, const std::vector<RebakeMesh>& meshes, const RebakeOptions& opt) {
  if (source.width == 0 || source.height == 0 || source.channels == 0 ||
      source.pixels.size() != size_t(source.width) * source.height * source.channels)
    throw std::invalid_argument("rebake: empty or inconsistent source image");
  if (opt.width == 0 || opt.height == 0) throw std::invalid_argument("rebake: zero output size");
  const int W = int(opt.width), H = int(opt.height);
  const int SW = int(source.width), SH = int(source.height);
  const int C = int(source.channels);
  RebakePlan plan;
  plan.width = W, plan.height = H, plan.channels = C;
  plan.has_alpha = C == 2 || C == 4;
  const bool has_alpha = plan.has_alpha;
  const int alpha = has_alpha ? C - 1 : -1;
  const int colour_channels = has_alpha ? C - 1 : C;
  const bool colour = opt.role == RebakeRole::Color;
  const bool linear = plan.linear = colour && opt.linear_light;
  const bool premultiply = plan.premultiplied = colour && has_alpha;

  // The working copy of the source: linear light and/or premultiplied for colour.
  std::vector<float>& work = plan.work;
  plan.source = &source;
  if (linear || premultiply) {
    work.resize(source.pixels.size());
    const auto& table = srgb_table();
    const size_t n = size_t(SW) * SH;
#pragma omp parallel for schedule(static)
    for (int64_t i = 0; i < int64_t(n); ++i) {
      const float* p = &source.pixels[size_t(i) * C];
      float* q = &work[size_t(i) * C];
      const float a = has_alpha ? p[alpha] : 1.0f;
      for (int c = 0; c < colour_channels; ++c) {
        float v = p[c];
        if (linear) v = table[size_t(std::clamp(v, 0.0f, 1.0f) * 65535.0f + 0.5f)];  // srgb_decode_fast
        q[c] = premultiply ? v * a : v;
      }
      if (has_alpha) q[alpha] = a;
    }
  }

  // Triangles in texel units.
  std::vector<Tri>& tris = plan.triangles;
  auto& rotation = plan.rotation;  // normal xy rotation old -> new, y-up
  for (const RebakeMesh& m : meshes) {
    if (!m.indices || !m.old_uv || !m.new_uv) continue;
    for (size_t t = 0; t + 2 < m.index_count; t += 3) {
      const uint32_t id[3] = {m.indices[t], m.indices[t + 1], m.indices[t + 2]};
      if (id[0] >= m.vertex_count || id[1] >= m.vertex_count || id[2] >= m.vertex_count) continue;
      Tri tr;
      float Q[2][2];
      double o[3][2];
      bool finite = true;
      for (int k = 0; k < 3; ++k) {
        tr.n[k][0] = double(m.new_uv[2 * id[k]]) * W;
        tr.n[k][1] = double(m.new_uv[2 * id[k] + 1]) * H;
        o[k][0] = double(m.old_uv[2 * id[k]]) * SW;
        o[k][1] = double(m.old_uv[2 * id[k] + 1]) * SH;
        finite = finite && std::isfinite(tr.n[k][0]) && std::isfinite(tr.n[k][1]) && std::isfinite(o[k][0]) &&
                 std::isfinite(o[k][1]);
      }
      if (!finite) continue;
      const double e1x = tr.n[1][0] - tr.n[0][0], e1y = tr.n[1][1] - tr.n[0][1];
      const double e2x = tr.n[2][0] - tr.n[0][0], e2y = tr.n[2][1] - tr.n[0][1];
      const double det = e1x * e2y - e2x * e1y;
      if (std::abs(det) < 1e-12) continue;
      tr.sign = det > 0 ? 1 : -1;
      // J = [o1-o0, o2-o0] [n1-n0, n2-n0]^-1
      const double f1x = o[1][0] - o[0][0], f1y = o[1][1] - o[0][1];
      const double f2x = o[2][0] - o[0][0], f2y = o[2][1] - o[0][1];
      const double inv[2][2] = {{e2y / det, -e2x / det}, {-e1y / det, e1x / det}};
      tr.J[0][0] = f1x * inv[0][0] + f2x * inv[1][0];
      tr.J[0][1] = f1x * inv[0][1] + f2x * inv[1][1];
      tr.J[1][0] = f1y * inv[0][0] + f2y * inv[1][0];
      tr.J[1][1] = f1y * inv[0][1] + f2y * inv[1][1];
      tr.o0[0] = o[0][0], tr.o0[1] = o[0][1];
      for (int a = 0; a < 2; ++a) {
        const double len = std::hypot(tr.J[0][a], tr.J[1][a]);
        tr.ns[a] = int(std::clamp(std::ceil(len - 1e-6), 1.0, double(std::clamp<uint32_t>(opt.max_samples, 1, 65535))));
      }
      // Normal rotation: polar factor of K = J^-1 (old -> new) in y-up components, S K S.
      const double dj = tr.J[0][0] * tr.J[1][1] - tr.J[0][1] * tr.J[1][0];
      if (dj != 0) {
        const double K[2][2] = {{tr.J[1][1] / dj, tr.J[0][1] / dj}, {tr.J[1][0] / dj, tr.J[0][0] / dj}};
        // S K S with S = diag(1,-1), K = [[J11, -J01], [-J10, J00]] / det: signs folded above.
        polar_factor(K, Q);
      } else {
        Q[0][0] = Q[1][1] = 1, Q[0][1] = Q[1][0] = 0;
      }
      for (int a = 0; a < 2; ++a) {
        tr.lo[a] = std::min({tr.n[0][a], tr.n[1][a], tr.n[2][a]});
        tr.hi[a] = std::max({tr.n[0][a], tr.n[1][a], tr.n[2][a]});
      }
      tris.push_back(tr);
      rotation.push_back({{{Q[0][0], Q[0][1]}, {Q[1][0], Q[1][1]}}});
    }
  }

  // Bin triangles into tiles (CSR, triangle order kept).
  constexpr int T = int(engine::kRebakeTile);
  const int tx = (W + T - 1) / T, ty = (H + T - 1) / T;
  auto tile_range = [&](const Tri& t, int& x0, int& x1, int& y0, int& y1) {
    x0 = std::max(0, int(std::floor(t.lo[0])) / T);
    x1 = std::min(tx - 1, int(std::min<double>(W - 1, std::ceil(t.hi[0]))) / T);
    y0 = std::max(0, int(std::floor(t.lo[1])) / T);
    y1 = std::min(ty - 1, int(std::min<double>(H - 1, std::ceil(t.hi[1]))) / T);
    return t.hi[0] > 0 && t.hi[1] > 0 && t.lo[0] < W && t.lo[1] < H;
  };
  std::vector<uint32_t>& start = plan.tile_start;
  start.assign(size_t(tx) * ty + 1, 0);
  for (const Tri& t : tris) {
    int x0, x1, y0, y1;
    if (!tile_range(t, x0, x1, y0, y1)) continue;
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) ++start[size_t(y) * tx + x + 1];
  }
  for (size_t i = 1; i < start.size(); ++i) start[i] += start[i - 1];
  std::vector<uint32_t>& list = plan.tile_list;
  list.assign(start.back(), 0);
  {
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    for (uint32_t i = 0; i < tris.size(); ++i) {
      int x0, x1, y0, y1;
      if (!tile_range(tris[i], x0, x1, y0, y1)) continue;
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) list[fill[size_t(y) * tx + x]++] = i;
    }
  }

  // UVs are floats: an edge meant to lie on a texel line may miss it by an ulp of the
  // texel coordinate. Overlaps thinner than that do not claim a texel.
  const double eps = 4.0 * std::numeric_limits<float>::epsilon() * std::max(W, H);

  // Owners: per texel, the candidate nearest to its centre among those overlapping it.
  std::vector<uint32_t>& owner = plan.owner;
  owner.assign(size_t(W) * H, engine::kRebakeNoOwner);
#pragma omp parallel for schedule(static)
  for (int tile = 0; tile < tx * ty; ++tile) {
    const int bx = (tile % tx) * T, by = (tile / tx) * T;
    const uint32_t* first = list.data() + start[tile];
    const uint32_t* last = list.data() + start[tile + 1];
    if (first == last) continue;
    for (int y = by; y < std::min(H, by + T); ++y)
      for (int x = bx; x < std::min(W, bx + T); ++x) {
        const double cx = x + 0.5, cy = y + 0.5;
        double best = std::numeric_limits<double>::infinity();
        const uint32_t* own = nullptr;
        for (const uint32_t* it = first; it != last; ++it) {
          const Tri& t = tris[*it];
          if (t.hi[0] <= x || t.lo[0] >= x + 1 || t.hi[1] <= y || t.lo[1] >= y + 1) continue;
          if (!triangle_overlaps_box(t.n[0], t.n[1], t.n[2], x, y, x + 1.0, y + 1.0, eps)) continue;
          double qx, qy;
          const double d = engine::rebake_closest_point(t, cx, cy, qx, qy);
          if (d < best) {
            best = d, own = it;
            if (d == 0) break;
          }
        }
        if (own) owner[size_t(y) * W + x] = uint32_t(own - list.data());
      }
  }
  return plan;
}

engine::RebakeTexelsDesc RebakePlan::desc(const RebakeOptions& opt) const {
  engine::RebakeTexelsDesc d;
  d.width = uint32_t(width), d.height = uint32_t(height);
  d.source = work.empty() ? source->pixels.data() : work.data();
  d.source_width = source->width, d.source_height = source->height, d.channels = source->channels;
  d.wrap_s = opt.wrap_s, d.wrap_t = opt.wrap_t;
  d.premultiplied = premultiplied;
  d.triangles = triangles.data(), d.triangle_count = triangles.size();
  d.tile_start = tile_start.data(), d.tile_list = tile_list.data();
  d.owner = owner.data();
  return d;
}

Image rebake(const Image& source, const std::vector<RebakeMesh>& meshes, const RebakeOptions& opt,
             engine::Engine& engine, RebakeStats* stats, const std::vector<uint8_t>* only) {
  const RebakePlan plan = plan_rebake(source, meshes, opt);
  const int W = plan.width, H = plan.height, C = plan.channels;
  const bool has_alpha = plan.has_alpha;
  const int alpha = has_alpha ? C - 1 : -1;
  const int colour_channels = has_alpha ? C - 1 : C;
  const bool linear = plan.linear;
  const bool normal = opt.role == RebakeRole::Normal && C >= 2;
  const auto& tris = plan.triangles;
  const auto& rotation = plan.rotation;
  const auto& list = plan.tile_list;
  const auto& owner = plan.owner;

  // The footprints, filtered on the engine: straight colour, linear. With `only`, the
  // engine sees the texels it marks as the only owned ones.
  engine::RebakeTexelsDesc desc = plan.desc(opt);
  std::vector<uint32_t> only_owner;
  bool any = !only;
  if (only) {
    if (only->size() != owner.size()) throw std::invalid_argument("rebake: `only` is not width x height");
    only_owner.assign(owner.size(), engine::kRebakeNoOwner);
    for (size_t i = 0; i < owner.size(); ++i)
      if ((*only)[i]) only_owner[i] = owner[i], any |= owner[i] != engine::kRebakeNoOwner;
    desc.owner = only_owner.data();
  }
  std::vector<float> filtered(size_t(W) * H * C, 0.0f);
  const Stopwatch t_sample;
  if (any) engine.rebake_texels(desc, filtered.data());
  const double sample_seconds = t_sample.seconds();

  Image out;
  out.width = opt.width, out.height = opt.height, out.channels = source.channels, out.bits = source.bits;
  out.pixels.assign(size_t(W) * H * C, 0.0f);
  std::vector<uint8_t> covered(size_t(W) * H, 0);
#pragma omp parallel for schedule(static)
  for (int64_t i = 0; i < int64_t(W) * H; ++i) {
    if (owner[size_t(i)] == engine::kRebakeNoOwner) continue;
    covered[size_t(i)] = 1;
    if (only && !(*only)[size_t(i)]) continue;
    const auto& Q = rotation[list[owner[size_t(i)]]];
    const float* f = &filtered[size_t(i) * C];
    float* o = &out.pixels[size_t(i) * C];
    if (normal) {
      double n[3] = {double(f[0]) * 2 - 1, double(f[1]) * 2 - 1, C >= 3 ? double(f[2]) * 2 - 1 : 0.0};
      const double rx = Q[0][0] * n[0] + Q[0][1] * n[1];
      const double ry = Q[1][0] * n[0] + Q[1][1] * n[1];
      n[0] = rx, n[1] = ry;
      if (C >= 3) {
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (len > 1e-12) n[0] /= len, n[1] /= len, n[2] /= len;
      } else {
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1]);
        if (len > 1) n[0] /= len, n[1] /= len;
      }
      const int nc = std::min(C, 3);
      for (int c = 0; c < nc; ++c) o[c] = float(std::clamp((n[c] + 1) * 0.5, 0.0, 1.0));
      for (int c = nc; c < C; ++c) o[c] = std::clamp(f[c], 0.0f, 1.0f);
    } else {
      for (int c = 0; c < colour_channels; ++c) {
        float v = std::clamp(f[c], 0.0f, 1.0f);
        if (linear) v = srgb_encode_fast(v);
        o[c] = v;
      }
      if (has_alpha) o[alpha] = std::clamp(f[alpha], 0.0f, 1.0f);
    }
  }

  size_t count = 0;
  for (uint8_t c : covered) count += c;
  if (opt.fill_gutter) fill_gutter(out, covered, opt.role == RebakeRole::Color);
  if (stats) {
    stats->covered = count;
    stats->triangles = tris.size();
    stats->footprint = covered;
    stats->coverage = std::move(covered);
    stats->sample_seconds = sample_seconds;
  }
  return out;
}

}  // namespace uvpress::atlas
