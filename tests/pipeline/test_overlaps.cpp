// Injectivity as an invariant: a chart whose fit runs over itself is kept at its input
// shape, and no written layout has UV overlaps the input did not have.
#include <catch2/catch.hpp>

#include "atlas/uv_overlap.h"
#include "engine.h"
#include "io/asset.h"
#include "io/gltf_append.h"
#include "io/gltf_io.h"
#include "io/image_io.h"
#include "perceptual/mesh_stage.h"
#include "pipeline/demo_asset.h"
#include "pipeline/injective_fit.h"
#include "pipeline/reparam.h"
#include "support.h"

#include <cmath>

using namespace uvpress;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A C-shaped strip: an annulus (radii 1 and 1.5) over `span` radians, `segments` quads
// around and `rings` across, two counter-clockwise triangles each. Points x y.
struct Strip {
  std::vector<double> points;
  std::vector<uint32_t> triangles;
  std::vector<double> radius_of_triangle;  // at the triangle's centre
  int segments = 0, rings = 0;
};

Strip c_strip(int segments, int rings, double span) {
  Strip s;
  s.segments = segments, s.rings = rings;
  for (int i = 0; i <= segments; ++i)
    for (int j = 0; j <= rings; ++j) {
      const double a = span * i / segments - span / 2, r = 1.0 + 0.5 * j / rings;
      s.points.push_back(r * std::cos(a)), s.points.push_back(r * std::sin(a));
    }
  auto id = [&](int i, int j) { return uint32_t(i * (rings + 1) + j); };
  for (int i = 0; i < segments; ++i)
    for (int j = 0; j < rings; ++j) {
      // (i, j) -> (i, j+1) is outward, (i, j) -> (i+1, j) counter-clockwise around.
      s.triangles.insert(s.triangles.end(), {id(i, j), id(i + 1, j + 1), id(i + 1, j)});
      s.triangles.insert(s.triangles.end(), {id(i, j), id(i, j + 1), id(i + 1, j + 1)});
      const double r = 1.0 + 0.5 * (j + 0.5) / rings;
      s.radius_of_triangle.push_back(r), s.radius_of_triangle.push_back(r);
    }
  return s;
}

// Targets that curl the strip: the inner fibres shrink along the strip (tangentially) to
// `inner`, the outer ones keep their length; no rotation preference. A bimetal strip: it
// bends tighter, and a C that is nearly closed runs its two arms into each other.
std::vector<perceptual::TriangleTarget> curling_targets(const Strip& s, double inner) {
  std::vector<perceptual::TriangleTarget> targets;
  for (size_t t = 0; t < s.triangles.size() / 3; ++t) {
    double centre[2] = {0, 0};
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 2; ++d) centre[d] += s.points[2 * s.triangles[3 * t + size_t(k)] + size_t(d)] / 3;
    const double a = std::atan2(centre[1], centre[0]);
    const double f = (s.radius_of_triangle[t] - 1.0) / 0.5;  // 0 inner .. 1 outer
    const double l = inner + (1 - inner) * (f > 0.5 ? 1.0 : 0.0);
    // S = V diag(l along the tangent, 1 across) V^T, the tangent at angle a + pi/2.
    const double c = std::cos(a + kPi / 2), sn = std::sin(a + kPi / 2);
    perceptual::TriangleTarget target;
    target.stretch = {c * c * l + sn * sn, c * sn * (l - 1), c * sn * (l - 1), sn * sn * l + c * c};
    target.weight_rotation = 0;
    target.weight_stretch = 1;
    targets.push_back(target);
  }
  return targets;
}

}  // namespace

TEST_CASE("overlaps: a chart whose fit would run over itself keeps its input shape", "[pipeline][overlap]") {
  // Nearly closed (351 degrees), its inner fibres shrunk to a tenth along the strip.
  const Strip s = c_strip(60, 4, 1.95 * kPi);
  std::vector<double> texels = s.points;
  for (double& x : texels) x *= 100;  // texel units, as reparam gives the mesh stage
  const auto targets = curling_targets(s, 0.1);
  const size_t n = s.triangles.size() / 3;

  // The mesh stage alone: flip-free, and yet its arms overlap.
  const auto raw = perceptual::fit_chart(texels, s.triangles, targets);
  REQUIRE(raw.status == perceptual::MeshStageStatus::Optimized);
  CHECK(raw.flips == 0);
  const auto pairs = atlas::find_new_overlaps(texels.data(), raw.uv.data(), s.triangles.data(), n);
  REQUIRE(!pairs.empty());

  // As reparam runs it: the overlap is seen and the chart keeps its input shape.
  const auto guarded = pipeline::fit_chart_injective(texels, s.triangles, targets);
  CHECK(guarded.fell_back());
  CHECK(guarded.overlap_pairs == pairs.size());
  CHECK(guarded.fit.uv == texels);
  CHECK(atlas::find_new_overlaps(texels.data(), guarded.fit.uv.data(), s.triangles.data(), n).empty());

  // A strip open wide enough curls without meeting itself: its fit is kept.
  const Strip open = c_strip(60, 4, 1.0 * kPi);
  std::vector<double> open_texels = open.points;
  for (double& x : open_texels) x *= 100;
  const auto kept = pipeline::fit_chart_injective(open_texels, open.triangles, curling_targets(open, 0.5));
  CHECK_FALSE(kept.fell_back());
  CHECK(kept.fit.uv != open_texels);
}

namespace {

// The demo asset with its sheet replaced by a flat C strip (UVs = positions, scaled into the
// unit square) and a texture that is flat inside radius 1.25 and fine noise outside: the
// triangle stage shrinks the flat inner half much more than the detailed outer half, and
// the mesh stage bends the strip with its two arms a few texels apart.
io::GltfFile c_strip_asset(const Strip& s, uint32_t texture_size) {
  io::GltfFile file = pipeline::make_demo_asset({4, int(texture_size)});
  auto& m = file.model;
  std::vector<float> positions, normals, uvs;
  for (size_t v = 0; v < s.points.size() / 2; ++v) {
    const double x = s.points[2 * v], y = s.points[2 * v + 1];
    positions.insert(positions.end(), {float(x), float(y), 0.0f});
    normals.insert(normals.end(), {0.0f, 0.0f, 1.0f});
    uvs.insert(uvs.end(), {float((x + 1.6) / 3.2), float((1.6 - y) / 3.2)});
  }
  std::vector<uint16_t> indices(s.triangles.begin(), s.triangles.end());
  auto& prim = m.meshes[0].primitives[0];
  prim.attributes["POSITION"] = io::append_float_accessor(m, positions, TINYGLTF_TYPE_VEC3);
  prim.attributes["NORMAL"] = io::append_float_accessor(m, normals, TINYGLTF_TYPE_VEC3);
  prim.attributes["TEXCOORD_0"] = io::append_float_accessor(m, uvs, TINYGLTF_TYPE_VEC2);
  prim.indices = io::append_index_accessor(m, indices);
  Image img;
  img.width = img.height = texture_size, img.channels = 3;
  img.pixels.resize(size_t(texture_size) * texture_size * 3);
  uint32_t seed = 12345;
  for (uint32_t y = 0; y < texture_size; ++y)
    for (uint32_t x = 0; x < texture_size; ++x) {
      const double px = (x + 0.5) / texture_size * 3.2 - 1.6, py = 1.6 - (y + 0.5) / texture_size * 3.2;
      const bool detail = std::hypot(px, py) > 1.25;
      for (uint32_t c = 0; c < 3; ++c) {
        seed = seed * 1664525u + 1013904223u;
        img.at(x, y, c) = detail ? float((seed >> 8) % 256) / 255.0f : 0.5f;
      }
    }
  file.image_bytes[0] = io::encode_image(img, "png");
  return file;
}

}  // namespace

TEST_CASE("overlaps: reparam's output of a nearly closed strip has no new overlaps", "[pipeline][reparam][overlap]") {
  auto engine = engine::make_cpu_engine({});
  const Strip s = c_strip(40, 4, 1.95 * kPi);
  io::GltfFile in = c_strip_asset(s, 256);
  io::GltfFile out = in;
  pipeline::ReparamOptions o;
  o.cost = 0.5;
  o.triangle.evaluations = 16;
  o.triangle.view_size = 16;
  o.candidates = false, o.guard = false, o.least_squares_bake = false;  // the paper's layout, written
  const pipeline::ReparamResult result = pipeline::reparam(out, *engine, o);
  auto report = result.to_json();
  INFO(report["warnings"].dump(1));
  CHECK(report["overlaps_new"] == 0);
  REQUIRE(!result.layouts.empty());
  CHECK(result.layouts[0].overlaps_new == 0);
  CHECK(report["flips"] == 0);
  // A chart that fell back is said so.
  if (report["overlap_fallback_charts"].get<size_t>() > 0) {
    bool warned = false;
    for (const auto& w : report["warnings"]) warned |= w.get<std::string>().find("ran over itself") != std::string::npos;
    CHECK(warned);
  }
  // Counted independently on the file as written.
  io::Asset a = io::build_asset(in), b = io::build_asset(out);
  const auto& before = a.primitives[0].uv_sets[0].uv;
  const auto& after = b.primitives[0].uv_sets[0].uv;
  const std::vector<double> u0(before.begin(), before.end()), u1(after.begin(), after.end());
  CHECK(atlas::find_new_overlaps(u0.data(), u1.data(), a.primitives[0].indices.data(), a.primitives[0].triangle_count()).empty());
}
