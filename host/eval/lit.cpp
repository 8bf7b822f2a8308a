// Lit shading for eval (see lit.h).
#include "lit.h"

#include "atlas/rebake.h"

#include <algorithm>
#include <cmath>

namespace uvpress::eval {

namespace {

using V3 = std::array<double, 3>;

V3 sub(const V3& a, const V3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
V3 add(const V3& a, const V3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
V3 mul(const V3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
double dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
V3 cross(const V3& a, const V3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double length(const V3& a) { return std::sqrt(dot(a, a)); }
V3 normalized(const V3& a) {
  const double l = length(a);
  return l > 0 ? mul(a, 1 / l) : a;
}
V3 at3(const std::vector<float>& v, size_t i) { return {v[3 * i], v[3 * i + 1], v[3 * i + 2]}; }
V3 at3(const float* v) { return {v[0], v[1], v[2]}; }

// Any unit vector perpendicular to unit n.
V3 perpendicular(const V3& n) {
  const V3 axis = std::abs(n[0]) < 0.9 ? V3{1, 0, 0} : V3{0, 1, 0};
  return normalized(cross(cross(n, axis), n));
}

constexpr double kPi = 3.14159265358979323846;

}  // namespace

const char* to_string(Shading s) { return s == Shading::Lit ? "lit" : s == Shading::Unlit ? "unlit" : "auto"; }

std::optional<Shading> parse_shading(std::string_view text) {
  if (text == "auto") return Shading::Auto;
  if (text == "unlit") return Shading::Unlit;
  if (text == "lit") return Shading::Lit;
  return std::nullopt;
}

LightRig default_light_rig() {
  // Irradiances in units of pi (a white Lambert surface facing the key has radiance 0.75):
  // key + ambient stay below 1 on white, so highlights clip only on speculars. The key
  // comes from above, in front and to the right (about 40 degrees above the horizon), the
  // fill from the left at half strength, the rim from behind and above: every one of the
  // 20 dodecahedron views sees surfaces lit at a grazing angle by one of them.
  LightRig rig;
  rig.lights = {{normalized({0.5, 0.8, 0.6}), 0.75 * kPi},
                {normalized({-0.9, 0.25, 0.35}), 0.35 * kPi},
                {normalized({0.15, 0.55, -0.85}), 0.45 * kPi}};
  rig.ambient = 0.12;
  return rig;
}

std::vector<float> vertex_tangents(const std::vector<float>& positions, const std::vector<float>& uvs,
                                   const std::vector<uint32_t>& indices, const std::vector<float>& normals) {
  const size_t n = positions.size() / 3;
  std::vector<V3> t_sum(n, V3{0, 0, 0}), v_sum(n, V3{0, 0, 0}), n_sum(n, V3{0, 0, 0});
  // Summed in triangle order (deterministic): each triangle's unit dP/du and dP/dv
  // weighted by its 3-D area, so that large triangles decide and tiny slivers do not.
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    const uint32_t a = indices[t], b = indices[t + 1], c = indices[t + 2];
    const V3 p0 = at3(positions, a), e1 = sub(at3(positions, b), p0), e2 = sub(at3(positions, c), p0);
    const double du1 = double(uvs[2 * b]) - uvs[2 * a], dv1 = double(uvs[2 * b + 1]) - uvs[2 * a + 1];
    const double du2 = double(uvs[2 * c]) - uvs[2 * a], dv2 = double(uvs[2 * c + 1]) - uvs[2 * a + 1];
    const V3 face = cross(e1, e2);
    const double area = 0.5 * length(face);
    for (uint32_t k : {a, b, c}) n_sum[k] = add(n_sum[k], mul(face, 0.5));
    const double r = du1 * dv2 - du2 * dv1;
    if (!(std::abs(r) > 1e-20) || !(area > 0)) continue;
    const V3 dpdu = mul(sub(mul(e1, dv2), mul(e2, dv1)), 1 / r);
    const V3 dpdv = mul(sub(mul(e2, du1), mul(e1, du2)), 1 / r);
    const V3 tu = mul(normalized(dpdu), area), tv = mul(normalized(dpdv), area);
    for (uint32_t k : {a, b, c}) t_sum[k] = add(t_sum[k], tu), v_sum[k] = add(v_sum[k], tv);
  }
  std::vector<float> out(4 * n, 0.0f);
  for (size_t v = 0; v < n; ++v) {
    V3 nv = normals.size() == 3 * n ? normalized(at3(normals, v)) : normalized(n_sum[v]);
    if (!(length(nv) > 0.5)) nv = {0, 0, 1};
    V3 t = sub(t_sum[v], mul(nv, dot(nv, t_sum[v])));
    t = length(t) > 1e-12 ? normalized(t) : perpendicular(nv);
    // The bitangent glTF builds, cross(N, T) w, should point toward -v (image up).
    const double w = dot(cross(nv, t), mul(v_sum[v], -1)) < 0 ? -1.0 : 1.0;
    for (int d = 0; d < 3; ++d) out[4 * v + size_t(d)] = float(t[size_t(d)]);
    out[4 * v + 3] = float(w);
  }
  return out;
}

std::array<double, 3> camera_eye(const std::array<float, 16>& m) {
  // Rows 0, 1 and 3 of M (E, 1) = 0: A E = -d, by Cramer's rule.
  const int rows[3] = {0, 1, 3};
  double A[3][3], d[3];
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) A[r][c] = m[size_t(4 * rows[r] + c)];
    d[r] = -double(m[size_t(4 * rows[r] + 3)]);
  }
  auto det3 = [](const double M[3][3]) {
    return M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1]) - M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0]) +
           M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0]);
  };
  const double D = det3(A);
  std::array<double, 3> e{0, 0, 0};
  for (int c = 0; c < 3; ++c) {
    double B[3][3];
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) B[r][k] = k == c ? d[r] : A[r][k];
    e[size_t(c)] = det3(B) / D;
  }
  return e;
}

std::array<double, 4> clip_of(const std::array<float, 16>& m, const float* p) {
  std::array<double, 4> c;
  for (int r = 0; r < 4; ++r)
    c[size_t(r)] = double(m[size_t(4 * r)]) * p[0] + double(m[size_t(4 * r + 1)]) * p[1] +
                   double(m[size_t(4 * r + 2)]) * p[2] + double(m[size_t(4 * r + 3)]);
  return c;
}

namespace {

using Clip = std::array<double, 4>;

// pixel_barycentrics from the corners' clip coordinates.
bool clip_barycentrics(const Clip* const c[3], uint32_t i, uint32_t j, uint32_t width, uint32_t height,
                       double weights[3]) {
  double sx[3], sy[3], w[3];
  for (int k = 0; k < 3; ++k) {
    const Clip& ck = *c[k];
    if (!(ck[3] > 0)) return false;  // behind the eye: eval's cameras frame the whole mesh
    sx[k] = ck[0] / ck[3], sy[k] = ck[1] / ck[3], w[k] = ck[3];
  }
  // The pixel centre in NDC (row 0 on top: y up).
  const double x = 2.0 * (i + 0.5) / width - 1.0, y = 1.0 - 2.0 * (j + 0.5) / height;
  const double area = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sx[2] - sx[0]) * (sy[1] - sy[0]);
  if (!(std::abs(area) > 1e-300)) return false;
  const double l0 = ((sx[1] - x) * (sy[2] - y) - (sx[2] - x) * (sy[1] - y)) / area;
  const double l1 = ((sx[2] - x) * (sy[0] - y) - (sx[0] - x) * (sy[2] - y)) / area;
  const double l[3] = {l0, l1, 1 - l0 - l1};
  // Screen-space weights are affine in 1/w: divide, renormalize.
  double sum = 0;
  for (int k = 0; k < 3; ++k) weights[k] = l[k] / w[k], sum += weights[k];
  if (!(std::abs(sum) > 0)) return false;
  for (int k = 0; k < 3; ++k) weights[k] /= sum;
  return true;
}

}  // namespace

bool pixel_barycentrics(const std::array<float, 16>& m, const float* p0, const float* p1, const float* p2, uint32_t i,
                        uint32_t j, uint32_t width, uint32_t height, double weights[3]) {
  const Clip c[3] = {clip_of(m, p0), clip_of(m, p1), clip_of(m, p2)};
  const Clip* const corners[3] = {&c[0], &c[1], &c[2]};
  return clip_barycentrics(corners, i, j, width, height, weights);
}

std::array<double, 3> shade(const LightRig& rig, const V3& n, const V3& v, const V3& base, double occlusion,
                            double roughness, double metallic, const V3& emissive) {
  roughness = std::clamp(roughness, 0.0, 1.0), metallic = std::clamp(metallic, 0.0, 1.0);
  V3 f0, c_diff;
  for (int c = 0; c < 3; ++c)
    f0[size_t(c)] = 0.04 * (1 - metallic) + base[size_t(c)] * metallic, c_diff[size_t(c)] = base[size_t(c)] * (1 - metallic);
  // alpha = roughness^2 (glTF), kept off 0: a perfect mirror under directional lights is a
  // delta that pixels never see.
  const double alpha = std::max(roughness * roughness, 1e-3), a2 = alpha * alpha;
  const double n_v = std::max(dot(n, v), 1e-4);
  V3 out{0, 0, 0};
  for (const auto& light : rig.lights) {
    const V3& l = light.direction;
    const double n_l = dot(n, l);
    if (!(n_l > 0)) continue;
    const V3 h = normalized(add(l, v));
    const double n_h = std::max(dot(n, h), 0.0), v_h = std::max(dot(v, h), 0.0);
    const double x = 1 - v_h, fresnel_w = x * x * x * x * x;
    const double dd = n_h * n_h * (a2 - 1) + 1;
    const double D = a2 / (kPi * dd * dd);
    const double vis = 0.5 / (n_l * std::sqrt(n_v * n_v * (1 - a2) + a2) + n_v * std::sqrt(n_l * n_l * (1 - a2) + a2));
    for (int c = 0; c < 3; ++c) {
      const double F = f0[size_t(c)] + (1 - f0[size_t(c)]) * fresnel_w;
      const double f = (1 - F) * c_diff[size_t(c)] / kPi + F * D * vis;
      out[size_t(c)] += f * light.irradiance * n_l;
    }
  }
  for (int c = 0; c < 3; ++c)
    out[size_t(c)] += rig.ambient * occlusion * (c_diff[size_t(c)] + f0[size_t(c)]) + emissive[size_t(c)];
  return out;
}

void lit_luminance(const LitSurface& s, const LightRig& rig, const std::array<float, 16>& camera, uint32_t width,
                   uint32_t height, const uint32_t* coverage, const std::vector<const float*>& maps, float* out) {
  const std::vector<float>& P = *s.positions;
  const std::vector<uint32_t>& ix = *s.indices;
  const bool smooth = s.normals.size() == P.size();
  const V3 eye = camera_eye(camera);
  // Every vertex's clip coordinates once per view (pixels share them).
  std::vector<Clip> clip(P.size() / 3);
  for (size_t v = 0; v < clip.size(); ++v) clip[v] = clip_of(camera, &P[3 * v]);
  for (uint32_t j = 0; j < height; ++j)
    for (uint32_t i = 0; i < width; ++i) {
      const size_t px = size_t(j) * width + i;
      const uint32_t t = coverage[px];
      if (t == 0xffffffffu) {  // engine::kNoMeshTriangle: background, as in the unlit views
        out[px] = 0.0f;
        continue;
      }
      const uint32_t c[3] = {ix[3 * size_t(t)], ix[3 * size_t(t) + 1], ix[3 * size_t(t) + 2]};
      double b[3];
      const V3 p0 = at3(P, c[0]), p1 = at3(P, c[1]), p2 = at3(P, c[2]);
      const V3 ng = normalized(cross(sub(p1, p0), sub(p2, p0)));
      const Clip* const corners[3] = {&clip[c[0]], &clip[c[1]], &clip[c[2]]};
      if (!clip_barycentrics(corners, i, j, width, height, b))
        b[0] = b[1] = b[2] = 1.0 / 3;
      // Snapped vertices let centres a hair outside in: clamp onto the triangle.
      double sum = 0;
      for (double& x : b) x = std::max(x, 0.0), sum += x;
      for (double& x : b) x /= sum;
      V3 pos{0, 0, 0}, N{0, 0, 0}, T{0, 0, 0};
      double w = 0;
      for (int k = 0; k < 3; ++k) {
        const size_t v = c[k];
        pos = add(pos, mul(at3(P, v), b[k]));
        if (smooth) N = add(N, mul(at3(s.normals, v), b[k]));
        T = add(T, mul(at3(&s.tangents[4 * v]), b[k]));
        w += b[k] * s.tangents[4 * v + 3];
      }
      if (!smooth || !(length(N) > 1e-12)) N = ng;
      const V3 V = normalized(sub(eye, pos));
      N = normalized(N);
      T = sub(T, mul(N, dot(N, T)));
      T = length(T) > 1e-12 ? normalized(T) : perpendicular(N);
      V3 B = mul(cross(N, T), w < 0 ? -1.0 : 1.0);
      // Back faces are lit as their front (double-sided): the whole frame flips, as glTF's
      // sample viewer does for !gl_FrontFacing (T, B and N; flipping N and T alone would
      // keep cross(N, T) and mirror the normal map's y).
      if (dot(ng, V) < 0) N = mul(N, -1), T = mul(T, -1), B = mul(B, -1);
      const LitMaterial& m = (*s.materials)[(*s.triangle_material)[t]];
      auto sample = [&](int map) { return map >= 0 ? maps[size_t(map)] + 3 * px : nullptr; };
      V3 n = N;
      if (const float* nm = sample(m.normal_map)) {
        const V3 nt = {(2.0 * nm[0] - 1) * m.normal_scale, (2.0 * nm[1] - 1) * m.normal_scale, 2.0 * nm[2] - 1};
        const V3 perturbed = add(add(mul(T, nt[0]), mul(B, nt[1])), mul(N, nt[2]));
        if (length(perturbed) > 1e-12) n = normalized(perturbed);
      }
      V3 base, emissive;
      const float* bc = sample(m.base_color_map);
      const float* em = sample(m.emissive_map);
      for (int k = 0; k < 3; ++k) {
        // The table decode (exact at 16-bit steps; samples between them are within 1e-5).
        base[size_t(k)] = m.base_color_factor[size_t(k)] * (bc ? atlas::srgb_decode_fast(bc[k]) : 1.0);
        emissive[size_t(k)] = m.emissive_factor[size_t(k)] * (em ? atlas::srgb_decode_fast(em[k]) : 1.0);
      }
      const float* occ = sample(m.occlusion_map);
      const float* mr = sample(m.metallic_roughness_map);
      const double occlusion = occ ? 1 + m.occlusion_strength * (double(occ[0]) - 1) : 1.0;
      const double roughness = m.roughness_factor * (mr ? double(mr[1]) : 1.0);
      const double metallic = m.metallic_factor * (mr ? double(mr[2]) : 1.0);
      const V3 rgb = shade(rig, n, V, base, occlusion, roughness, metallic, emissive);
      // Displayed values, then GMSD step 1 on them as the unlit path does.
      float y = 0;
      const float weights[3] = {0.299f, 0.587f, 0.114f};
      for (int k = 0; k < 3; ++k)
        y += weights[k] * atlas::srgb_encode_fast(float(std::clamp(rgb[size_t(k)], 0.0, 1.0)));  // error < 2e-6
      out[px] = y;
    }
}

}  // namespace uvpress::eval
