// eval --shading lit (issue 14 item 5): the lit views see a normal map's detail that the
// unlit q cannot, assets without normal maps keep their figures, and the per-pixel
// geometry (barycentrics, interpolated frames) agrees with a double-precision reference.
// `uvpress eval --shading` itself: tests/cli/test_eval.cpp.
#include <catch2/catch.hpp>

#include "core/image.h"
#include "engine.h"
#include "eval/bumpy_sheet.h"
#include "eval/eval.h"
#include "eval/lit.h"
#include "pipeline/demo_asset.h"
#include "pipeline/reparam.h"
#include "support.h"

#include <Eigen/Dense>

#include <chrono>
#include <cmath>

using namespace uvpress;
using test::bumpy_sheet;

namespace {

constexpr double kPi = 3.14159265358979323846;

const eval::CurvePoint& curve_point(const eval::EvalResult& report, double c_r) {
  for (const auto& p : report.layouts[0].curve)
    if (std::abs(p.c_r - c_r) < 1e-9) return p;
  FAIL("no curve point at c_r " << c_r);
  return report.layouts[0].curve[0];
}

}  // namespace

TEST_CASE("lit q sees a halved normal map that the unlit q cannot", "[eval][lit]") {
  auto engine = engine::make_cpu_engine({});
  const io::GltfFile asset = bumpy_sheet(true);
  eval::EvalOptions o;
  o.cost_grid = {0.25, 1.0};
  o.artifacts = false;
  auto t0 = std::chrono::steady_clock::now();
  const eval::EvalResult lit = eval::evaluate(asset, {}, *engine, o);  // auto: the asset has a normal map
  const double lit_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  REQUIRE(lit.lit);
  REQUIRE(lit.shading_requested == eval::Shading::Auto);
  const double floor_unlit = lit.noise_floor_unlit, floor_lit = lit.noise_floor_lit;
  REQUIRE(lit.noise_floor() == floor_lit);
  const auto& quarter = curve_point(lit, 0.25);
  const auto& full = curve_point(lit, 1.0);
  REQUIRE(quarter.q == quarter.q_lit);
  // (1) The base colour is flat: nothing for the unlit q to see at any cost.
  // (A flat texture's Lanczos resize rounds in fp32 (1e-7), which GMSD sees at 1e-9,
  // hence the absolute allowance beside the measured floor.)
  CHECK(std::abs(quarter.q_unlit - full.q_unlit) <= std::max(floor_unlit, 1e-6));
  // (2) The bumps are 2 texels wide: at half the side they are gone, and the lit views show it.
  CHECK(full.q_lit == Approx(0).margin(1e-6));  // the same size copies exactly
  CHECK(quarter.q_lit - full.q_lit > 3 * floor_lit);
  CHECK(quarter.q_lit > 1e-3);

  // The unlit q of a lit evaluation is the unlit evaluation's: to fp32 rounding, since an
  // unlit curve samples its costs from one rasterization (Engine::render_mesh_textures) and
  // a lit one renders each cost on its own (render_mesh).
  o.shading = eval::Shading::Unlit;
  t0 = std::chrono::steady_clock::now();
  const eval::EvalResult unlit = eval::evaluate(asset, {}, *engine, o);
  const double unlit_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  REQUIRE(!unlit.lit);
  // (Curves: each evaluation keeps the input resize its own q prefers, so compare the
  // noise floors, measured with one resize, and the as-written scores below.)
  // (This asset's base colour is flat: its unlit floor, 5e-10, is fp32 rounding itself,
  // which the two render paths round differently, hence the absolute allowance.)
  CHECK(unlit.noise_floor() == Approx(floor_unlit).epsilon(1e-4).margin(1e-8));
  WARN("lit eval " << lit_seconds << " s, unlit " << unlit_seconds << " s (" << lit_seconds / unlit_seconds
                   << "x); lit q at c_r 0.25 " << quarter.q_lit << " (floor " << floor_lit
                   << "), unlit " << quarter.q_unlit << " (floor " << floor_unlit << ")");

  // The as-written scorer (reparam's guard) uses the lit q on this asset, and its unlit q
  // is the unlit scorer's, bit for bit.
  eval::EvalOptions so;
  so.noise_floor = false;
  eval::AsWrittenScorer scorer(asset, *engine, so);
  REQUIRE(scorer.shading() == eval::Shading::Lit);
  const eval::Scored self = scorer.score(asset);
  CHECK(self.lit);
  CHECK(self.q == self.q_lit);
  CHECK(self.q_lit == Approx(0).margin(1e-6));
  const io::GltfFile coarse = bumpy_sheet(true, 64);  // the same surface, other maps
  const eval::Scored lit_coarse = scorer.score(coarse);
  so.shading = eval::Shading::Unlit;
  const eval::Scored unlit_coarse = eval::AsWrittenScorer(asset, *engine, so).score(coarse);
  CHECK(!unlit_coarse.lit);
  CHECK(lit_coarse.q_unlit == unlit_coarse.q);
  CHECK(lit_coarse.q_lit > 0.01);
}

TEST_CASE("assets without a normal map keep bit-identical figures under --shading auto", "[eval][lit]") {
  auto engine = engine::make_cpu_engine({});
  pipeline::DemoOptions d;
  d.grid = 16, d.texture_size = 128;
  const io::GltfFile demo = pipeline::make_demo_asset(d);
  eval::EvalOptions o;
  o.cost_grid = {0.3, 0.6};
  o.artifacts = false;
  o.noise_floor = false;
  const eval::EvalResult automatic = eval::evaluate(demo, {}, *engine, o);
  o.shading = eval::Shading::Unlit;
  const eval::EvalResult unlit = eval::evaluate(demo, {}, *engine, o);
  REQUIRE(!automatic.lit);
  REQUIRE(!automatic.to_json()["layouts"][0]["curve"][0].contains("q_lit"));  // the report has no lit keys
  for (size_t k = 0; k < 2; ++k) {
    CHECK(automatic.layouts[0].curve[k].q == unlit.layouts[0].curve[k].q);
    CHECK(automatic.layouts[0].curve[k].q_views == unlit.layouts[0].curve[k].q_views);
  }
  // Lit on request: the demo's base colour under the rig (no maps but the base colour).
  o.shading = eval::Shading::Lit;
  const eval::EvalResult lit = eval::evaluate(demo, {}, *engine, o);
  REQUIRE(lit.lit);
  // Its unlit q is the unlit evaluation's, to the fp32 rounding of the unlit curve's
  // shared rasterization (Engine::render_mesh_textures; the lit curve renders each cost).
  CHECK(lit.layouts[0].curve[0].q_unlit == Approx(unlit.layouts[0].curve[0].q).epsilon(1e-5));
  CHECK(lit.layouts[0].curve[0].q_lit > 0);
}

TEST_CASE("lit shading: a normal map on another UV set or that does not decode falls back to unlit under auto, fails under lit",
          "[eval][lit]") {
  auto engine = engine::make_cpu_engine({});
  io::GltfFile asset = bumpy_sheet(true, 32, 4);
  asset.model.materials[0].normalTexture.texCoord = 1;
  // TEXCOORD_1: the same UVs, another set: eval renders one set and must say it skipped lighting.
  auto& prim = asset.model.meshes[0].primitives[0];
  prim.attributes["TEXCOORD_1"] = prim.attributes["TEXCOORD_0"];
  eval::EvalOptions o;
  o.cost_grid = {1.0};
  o.artifacts = false, o.noise_floor = false;
  o.resolution = 64;
  const eval::EvalResult r = eval::evaluate(asset, {}, *engine, o);
  CHECK(!r.lit);
  CHECK(r.shading_warning.find("TEXCOORD_1") != std::string::npos);
  o.shading = eval::Shading::Lit;
  CHECK_THROWS_WITH(eval::evaluate(asset, {}, *engine, o), Catch::Contains("cannot evaluate lit"));

  // A normal map that does not decode: the same (the unlit q never read it).
  io::GltfFile broken = bumpy_sheet(true, 32, 4);
  broken.image_bytes[1] = {0x89, 'P', 'N', 'G', 0, 1, 2, 3};
  o.shading = eval::Shading::Auto;
  const eval::EvalResult b = eval::evaluate(broken, {}, *engine, o);
  CHECK(!b.lit);
  CHECK(b.shading_warning.find("normalTexture") != std::string::npos);
  o.shading = eval::Shading::Lit;
  CHECK_THROWS_WITH(eval::evaluate(broken, {}, *engine, o), Catch::Contains("cannot evaluate lit"));
}

TEST_CASE("lit_luminance: barycentrics, interpolated normals and the tangent frame against a double reference",
          "[eval][lit]") {
  // Two triangles of the plane z = 0.2 x (tilted), UV u along +x, v along -y; vertex normals
  // that vary (so interpolation matters), one light, no ambient.
  const std::vector<float> P = {-1, -1, -0.2f, 1, -1, 0.2f, 1, 1, 0.2f, -1, 1, -0.2f};
  const std::vector<float> UV = {0, 1, 1, 1, 1, 0, 0, 0};
  const std::vector<uint32_t> I = {0, 1, 2, 0, 2, 3};
  std::vector<float> N;
  for (int v = 0; v < 4; ++v) {
    Eigen::Vector3d n(-0.2 + 0.15 * P[3 * size_t(v)], 0.1 * P[3 * size_t(v) + 1], 1.0);
    n.normalize();
    N.insert(N.end(), {float(n.x()), float(n.y()), float(n.z())});
  }
  const auto cams = eval::dodecahedron_cameras(P.data(), 4);
  auto check_view = [&](bool back) {
    // The camera most in front of (back: behind) the plane (largest eye z over distance)
    // that is not straight on (|x| > 0.3 of the distance).
    const double sgn = back ? -1.0 : 1.0;
    std::array<float, 16> cam{};
    double best = 0;
    for (const auto& c : cams) {
      const auto e = eval::camera_eye(c);
      const double d = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
      if (std::abs(e[0]) > 0.3 * d && sgn * e[2] / d > best) cam = c, best = sgn * e[2] / d;
    }
    REQUIRE(best > 0.5);
    Eigen::Matrix4d M;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) M(r, c) = cam[size_t(4 * r + c)];
    const Eigen::Matrix4d Mi = M.inverse();
    const Eigen::Vector4d eh = Mi * Eigen::Vector4d(0, 0, 1, 0);
    const Eigen::Vector3d eye = eh.head<3>() / eh.w();
    const auto e = eval::camera_eye(cam);
    CHECK((eye - Eigen::Vector3d(e[0], e[1], e[2])).norm() < 1e-6 * eye.norm());

    eval::LightRig rig;
    rig.lights = {{{0.3, 0.2, 0.93 * sgn}, kPi}};  // on the camera's side
    const double l = std::sqrt(0.3 * 0.3 + 0.2 * 0.2 + 0.93 * 0.93);
    for (double& x : rig.lights[0].direction) x /= l;
    rig.ambient = 0;
    std::vector<eval::LitMaterial> materials(1);
    materials[0].base_color_factor = {0.5, 0.7, 0.9, 1};
    materials[0].metallic_factor = 0.2, materials[0].roughness_factor = 0.5;
    materials[0].normal_map = 0;
    const std::vector<uint32_t> tri_material = {0, 0};
    eval::LitSurface surface;
    surface.positions = &P, surface.indices = &I, surface.normals = N;
    surface.tangents = eval::vertex_tangents(P, UV, I, N);
    surface.triangle_material = &tri_material, surface.materials = &materials;
    // The derived tangent runs along +u = +x (in the plane), handedness +1 (v runs down y).
    for (int v = 0; v < 4; ++v) {
      CHECK(surface.tangents[4 * size_t(v)] > 0.9f);
      CHECK(surface.tangents[4 * size_t(v) + 3] == 1.0f);
    }

    const Eigen::Vector3d dpdu = Eigen::Vector3d(1, 0, 0.2).normalized();
    auto vertex_tangent = [&](uint32_t v) {
      const Eigen::Vector3d n(N[3 * v], N[3 * v + 1], N[3 * v + 2]);
      return Eigen::Vector3d((dpdu - n * n.dot(dpdu)).normalized());
    };
    for (uint32_t v = 0; v < 4; ++v)
      CHECK((vertex_tangent(v) - Eigen::Vector3d(surface.tangents[4 * v], surface.tangents[4 * v + 1], surface.tangents[4 * v + 2])).norm() < 1e-6);

    constexpr uint32_t R = 64;
    // A constant tilted tangent-space normal (+X: toward +u), as a map render would give it.
    const Eigen::Vector3d nt = Eigen::Vector3d(0.3, -0.2, 1).normalized();
    std::vector<float> map(size_t(R) * R * 3);
    for (size_t p = 0; p < size_t(R) * R; ++p)
      for (int c = 0; c < 3; ++c) map[3 * p + size_t(c)] = float(nt[c] * 0.5 + 0.5);
    // Coverage and the reference from the exact ray-plane intersection (double).
    std::vector<uint32_t> coverage(size_t(R) * R, engine::kNoMeshTriangle);
    std::vector<double> expected(size_t(R) * R, 0.0);
    size_t checked = 0;
    for (uint32_t j = 0; j < R; ++j)
      for (uint32_t i = 0; i < R; ++i) {
        const double x = 2.0 * (i + 0.5) / R - 1, y = 1 - 2.0 * (j + 0.5) / R;
        Eigen::Vector4d a = Mi * Eigen::Vector4d(x, y, -1, 1), b = Mi * Eigen::Vector4d(x, y, 1, 1);
        const Eigen::Vector3d o = a.head<3>() / a.w(), d = b.head<3>() / b.w() - o;
        // Plane z = 0.2 x: (o + s d).z - 0.2 (o + s d).x = 0.
        const double s = -(o.z() - 0.2 * o.x()) / (d.z() - 0.2 * d.x());
        const Eigen::Vector3d X = o + s * d;
        for (uint32_t t = 0; t < 2; ++t) {
          Eigen::Vector3d p[3];
          for (int k = 0; k < 3; ++k) p[k] = Eigen::Vector3d(P[3 * I[3 * t + k]], P[3 * I[3 * t + k] + 1], P[3 * I[3 * t + k] + 2]);
          const Eigen::Vector3d n = (p[1] - p[0]).cross(p[2] - p[0]);
          double w[3];
          for (int k = 0; k < 3; ++k) w[k] = (p[(k + 2) % 3] - p[(k + 1) % 3]).cross(X - p[(k + 1) % 3]).dot(n) / n.squaredNorm();
          if (std::min({w[0], w[1], w[2]}) < 1e-3) continue;  // clear of edges only
          coverage[size_t(j) * R + i] = t;
          Eigen::Vector3d Nv(0, 0, 0);
          for (int k = 0; k < 3; ++k) Nv += w[k] * Eigen::Vector3d(N[3 * I[3 * t + k]], N[3 * I[3 * t + k] + 1], N[3 * I[3 * t + k] + 2]);
          Nv.normalize();
          // The frame: each vertex's tangent dP/du made perpendicular to its normal,
          // interpolated, made perpendicular to N; B = N x T (handedness +1).
          Eigen::Vector3d T(0, 0, 0);
          for (int k = 0; k < 3; ++k) T += w[k] * vertex_tangent(I[3 * t + k]);
          T = (T - Nv * Nv.dot(T)).normalized();
          const Eigen::Vector3d B = Nv.cross(T);
          // A back face is lit as a front one: its whole frame flipped (glTF's doubleSided).
          const Eigen::Vector3d n_world = sgn * (T * nt.x() + B * nt.y() + Nv * nt.z()).normalized();
          const Eigen::Vector3d V = (eye - X).normalized();
          const auto rgb = eval::shade(rig, {n_world.x(), n_world.y(), n_world.z()}, {V.x(), V.y(), V.z()}, {0.5, 0.7, 0.9},
                                       1.0, 0.5, 0.2, {0, 0, 0});
          double Y = 0;
          const double weights[3] = {0.299, 0.587, 0.114};
          for (int c = 0; c < 3; ++c) {
            const double v = std::clamp(rgb[size_t(c)], 0.0, 1.0);
            Y += weights[c] * (v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055);
          }
          expected[size_t(j) * R + i] = Y;
          ++checked;
        }
      }
    REQUIRE(checked > R * R / 8);
    std::vector<float> out(size_t(R) * R, -1.0f);
    eval::lit_luminance(surface, rig, cam, R, R, coverage.data(), {map.data()}, out.data());
    double worst = 0;
    for (size_t p = 0; p < out.size(); ++p) {
      if (coverage[p] == engine::kNoMeshTriangle) {
        CHECK(out[p] == 0.0f);
        continue;
      }
      worst = std::max(worst, std::abs(double(out[p]) - expected[p]));
    }
    // fp32 vertex data, map samples and output: far inside one 8-bit level.
    CHECK(worst < 2e-4);
  };
  check_view(false);
  check_view(true);

  // The BRDF itself at normal incidence, roughness 1, dielectric: D = 1/pi, V = 1/4, F = 0.04.
  eval::LightRig head_on;
  head_on.lights = {{{0, 0, 1}, kPi}};
  const auto rgb = eval::shade(head_on, {0, 0, 1}, {0, 0, 1}, {0.5, 0.5, 0.5}, 1, 1, 0, {0, 0, 0});
  CHECK(rgb[0] == Approx((0.96 * 0.5 / kPi + 0.04 / kPi * 0.25) * kPi).epsilon(1e-12));
}

TEST_CASE("reparam's candidates and guard score a normal-mapped asset lit", "[eval][lit][reparam]") {
  auto engine = engine::make_cpu_engine({});
  io::GltfFile file = bumpy_sheet(true, 128, 12);
  pipeline::ReparamOptions o;
  o.optimize = false;  // only repack: the scoring is what is under test
  o.cost = 0.25;
  o.score_resolution = 256;
  const auto report = pipeline::reparam(file, *engine, o).to_json();
  REQUIRE(report.contains("scoring"));
  CHECK(report["scoring"]["shading"] == "lit");
  // The resize to a quarter of the texels loses the 2-texel bumps: the lit guard sees it
  // (unlit, the flat base colour would score it 0).
  REQUIRE(report["guard"].contains("q_resize"));
  CHECK(report["guard"]["q_resize"].get<double>() > 0.01);
  // --score-shading unlit: the old figures, blind to the normal map.
  io::GltfFile again = bumpy_sheet(true, 128, 12);
  o.score_shading = eval::Shading::Unlit;
  const auto unlit = pipeline::reparam(again, *engine, o).to_json();
  CHECK(unlit["scoring"]["shading"] == "unlit");
  CHECK(unlit["guard"]["q_resize"].get<double>() < 1e-6);
}

TEST_CASE("lit q: Vulkan (lavapipe) renders agree with the CPU oracle", "[eval][lit][engine]") {
  UVPRESS_LAVAPIPE_OR_SKIP(vk);
  auto cpu = engine::make_cpu_engine({});
  const io::GltfFile asset = bumpy_sheet(true, 64, 8);
  eval::EvalOptions o;
  o.cost_grid = {0.25};
  o.resolution = 128;
  o.artifacts = false, o.noise_floor = false;
  const eval::EvalResult a = eval::evaluate(asset, {}, *cpu, o), b = eval::evaluate(asset, {}, *vk, o);
  REQUIRE(a.lit);
  REQUIRE(b.lit);
  const double qa = a.layouts[0].curve[0].q_lit, qb = b.layouts[0].curve[0].q_lit;
  REQUIRE(qa > 0.01);
  // The lighting runs on the host either way; the map renders agree to fp32 sampling
  // (coverage is integer rasterization, the same on both).
  CHECK(std::abs(qa - qb) < 1e-3 * qa);
  CHECK(vk->validation_errors() == 0);
}
