// Layout extraction, re-baking and the isometric layout for eval (see layout.h).
#include "layout.h"

#include "atlas/charts.h"
#include "atlas/rebake.h"
#include "core/error.h"
#include "core/stopwatch.h"
#include "flatten/flatten.h"
#include "io/asset.h"
#include "io/image_io.h"
#include "io/vertex_attribute.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <set>

namespace uvpress::eval::detail {

namespace {

Image to_rgb(const Image& in) {
  Image out;
  out.width = in.width, out.height = in.height, out.channels = 3, out.bits = in.bits;
  out.pixels.resize(size_t(in.width) * in.height * 3);
  for (size_t i = 0; i < size_t(in.width) * in.height; ++i)
    for (uint32_t c = 0; c < 3; ++c)
      out.pixels[3 * i + c] = in.pixels[i * in.channels + (in.channels >= 3 ? c : 0)];
  return out;
}

}  // namespace

double uv_area(const std::vector<float>& uv, const std::vector<uint32_t>& ix, size_t t) {
  const float* a = &uv[2 * size_t(ix[3 * t])];
  const float* b = &uv[2 * size_t(ix[3 * t + 1])];
  const float* c = &uv[2 * size_t(ix[3 * t + 2])];
  return 0.5 * std::abs((double(b[0]) - a[0]) * (double(c[1]) - a[1]) - (double(c[0]) - a[0]) * (double(b[1]) - a[1]));
}

double area3d(const std::vector<float>& p, const std::vector<uint32_t>& ix, size_t t) {
  double e1[3], e2[3];
  for (int d = 0; d < 3; ++d) {
    e1[d] = double(p[3 * size_t(ix[3 * t + 1]) + size_t(d)]) - p[3 * size_t(ix[3 * t]) + size_t(d)];
    e2[d] = double(p[3 * size_t(ix[3 * t + 2]) + size_t(d)]) - p[3 * size_t(ix[3 * t]) + size_t(d)];
  }
  const double x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2], z = e1[0] * e2[1] - e1[1] * e2[0];
  return 0.5 * std::sqrt(x * x + y * y + z * z);
}

bool has_normal_map(const io::GltfFile& file) {
  for (const auto& m : file.model.materials)
    if (m.normalTexture.index >= 0) return true;
  return false;
}

namespace {

bool same_transform(const io::TextureTransform& a, const io::TextureTransform& b) {
  if (!a.present && !b.present) return true;
  return a.present == b.present && a.offset == b.offset && a.scale == b.scale && a.rotation == b.rotation;
}

// What lit shading needs of `m`'s primitives (see LayoutMesh). `driving` is each layout
// primitive's use of the driving texture, in layout order.
void add_lit_inputs(const io::GltfFile& file, const io::Asset& asset, const std::vector<const io::ImageUse*>& driving,
                    LayoutMesh& m) {
  const auto& model = file.model;
  // Normals and tangents: kept only when every primitive has them (a mix is lit with flat
  // normals / derived tangents throughout: rare, and never wrong in a way that differs
  // between layouts of one asset).
  std::vector<float> normals, tangents;
  bool all_normals = true, all_tangents = true;
  for (const io::ImageUse* use : driving) {
    const auto& prim = asset.primitives[size_t(use->primitive)];
    auto n = io::vertex_attribute(file, prim.mesh, prim.primitive, "NORMAL", 3);
    auto t = io::vertex_attribute(file, prim.mesh, prim.primitive, "TANGENT", 4);
    all_normals = all_normals && !n.empty(), all_tangents = all_tangents && !t.empty();
    normals.insert(normals.end(), n.begin(), n.end()), tangents.insert(tangents.end(), t.begin(), t.end());
  }
  if (all_normals) m.normals = std::move(normals);
  if (all_tangents) m.tangents = std::move(tangents);
  // Materials (glTF index -> entry, in order of first use; -1 is the default material).
  std::map<int, uint32_t> material_of;
  std::map<std::pair<int, int>, int> map_of;  // (image, kind) -> index into m.maps
  for (const io::ImageUse* use : driving) {
    const auto& prim = asset.primitives[size_t(use->primitive)];
    auto [it, fresh] = material_of.insert({prim.material, uint32_t(m.materials.size())});
    if (fresh) {
      LitMaterial lm;
      if (prim.material >= 0) {
        const auto& gm = model.materials[size_t(prim.material)];
        const auto& pbr = gm.pbrMetallicRoughness;
        for (size_t c = 0; c < 4 && c < pbr.baseColorFactor.size(); ++c) lm.base_color_factor[c] = pbr.baseColorFactor[c];
        lm.metallic_factor = pbr.metallicFactor, lm.roughness_factor = pbr.roughnessFactor;
        lm.normal_scale = gm.normalTexture.scale, lm.occlusion_strength = gm.occlusionTexture.strength;
        for (size_t c = 0; c < 3 && c < gm.emissiveFactor.size(); ++c) lm.emissive_factor[c] = gm.emissiveFactor[c];
      }
      m.materials.push_back(lm);
    }
    LitMaterial& lm = m.materials[it->second];
    for (size_t t = 0; t < prim.triangle_count(); ++t) m.triangle_material.push_back(it->second);
    if (!fresh) continue;
    // The material's maps, each through this primitive's UVs.
    for (const auto& img : asset.images)
      for (const auto& u : img.uses) {
        if (u.primitive != use->primitive || u.role == io::TextureRole::Other) continue;
        const std::string slot = "material " + std::to_string(u.material) + " " + u.slot;
        if (u.tex_coord != use->tex_coord || !same_transform(u.transform, use->transform)) {
          if (m.lit_problem.empty())
            m.lit_problem = slot + " samples other UVs (TEXCOORD_" + std::to_string(u.tex_coord) +
                            " or another transform) than the driving texture: eval renders one UV set";
          continue;
        }
        const atlas::RebakeRole kind = u.role == io::TextureRole::Normal ? atlas::RebakeRole::Normal
                                       : (u.role == io::TextureRole::BaseColor || u.role == io::TextureRole::Emissive)
                                           ? atlas::RebakeRole::Color
                                           : atlas::RebakeRole::Data;
        auto [mit, new_map] = map_of.insert({{img.index, int(kind)}, int(m.maps.size())});
        if (new_map) {
          MaterialMap map;
          map.image = img.index, map.kind = kind;
          Image decoded;
          try {
            decoded = io::decode_image(file.image_bytes.at(size_t(img.index)),
                                       file.path + " image " + std::to_string(img.index));
          } catch (const InputError& e) {
            // A map the unlit q never read: no reason to fail what used to work; the caller
            // says why lighting is off (or fails when lit was asked for).
            if (m.lit_problem.empty()) m.lit_problem = slot + ": " + e.what();
            decoded.width = decoded.height = 1, decoded.channels = 3, decoded.pixels = {0.5f, 0.5f, 1.0f};
          }
          if (kind == atlas::RebakeRole::Normal && decoded.channels < 3 && m.lit_problem.empty())
            m.lit_problem = slot + ": image " + std::to_string(img.index) + " has " + std::to_string(decoded.channels) +
                            " channel(s), a normal map needs RGB";
          map.full = to_rgb(decoded);
          m.maps.push_back(std::move(map));
        }
        switch (u.role) {
          case io::TextureRole::BaseColor: lm.base_color_map = mit->second; break;
          case io::TextureRole::Normal: lm.normal_map = mit->second; break;
          case io::TextureRole::Occlusion: lm.occlusion_map = mit->second; break;
          case io::TextureRole::MetallicRoughness: lm.metallic_roughness_map = mit->second; break;
          case io::TextureRole::Emissive: lm.emissive_map = mit->second; break;
          default: break;
        }
      }
  }
}

}  // namespace

LayoutMesh extract_layout(const io::GltfFile& file, const std::string& name, bool lit, int image_index) {
  io::Asset asset = io::build_asset(file);
  // The driving texture: base colour first, then the most triangles sampling it.
  int best = -1;
  std::pair<int, size_t> best_score{-1, 0};
  for (const auto& img : asset.images) {
    std::set<int> prims;
    bool color = false;
    for (const auto& use : img.uses) {
      const auto& prim = asset.primitives[size_t(use.primitive)];
      if (size_t(use.tex_coord) >= prim.uv_sets.size()) continue;
      prims.insert(use.primitive);
      color = color || use.role == io::TextureRole::BaseColor;
    }
    size_t tris = 0;
    for (int p : prims) tris += asset.primitives[size_t(p)].triangle_count();
    if (tris == 0) continue;
    std::pair<int, size_t> score{color ? 1 : 0, tris};
    if (image_index >= 0) score = {img.index == image_index ? 1 : 0, img.index == image_index ? tris : 0};
    if (score > best_score) best_score = score, best = img.index;
  }
  if (image_index >= 0 && best != image_index)
    throw InputError(file.path, "no triangle primitive samples image " + std::to_string(image_index) + ": nothing to evaluate");
  if (best < 0) throw InputError(file.path, "no triangle primitive samples a texture: nothing to evaluate");
  LayoutMesh m;
  m.name = name, m.file = file.path, m.image = best, m.texture_source = "original";
  const io::AssetImage* image = nullptr;
  for (const auto& img : asset.images)
    if (img.index == best) image = &img;
  std::set<int> done;
  std::vector<const io::ImageUse*> driving;  // per layout primitive, in order
  for (const auto& use : image->uses) {
    const auto& prim = asset.primitives[size_t(use.primitive)];
    if (size_t(use.tex_coord) >= prim.uv_sets.size() || !done.insert(use.primitive).second) continue;
    driving.push_back(&use);
    if (done.size() == 1) m.repeat = use.wrap_s == 10497 && use.wrap_t == 10497;
    const uint32_t base = uint32_t(m.positions.size() / 3);
    m.positions.insert(m.positions.end(), prim.positions.begin(), prim.positions.end());
    const auto& uv = prim.uv_sets[size_t(use.tex_coord)].uv;
    for (size_t v = 0; v < prim.vertex_count(); ++v) {
      auto t = use.transform.present ? use.transform.apply(uv[2 * v], uv[2 * v + 1])
                                     : std::array<float, 2>{uv[2 * v], uv[2 * v + 1]};
      m.uvs.push_back(t[0]), m.uvs.push_back(t[1]);
    }
    for (uint32_t i : prim.indices) m.indices.push_back(base + i);
  }
  m.full = to_rgb(io::decode_image(file.image_bytes.at(size_t(best)), file.path + " image " + std::to_string(best)));
  for (size_t t = 0; t < m.indices.size() / 3; ++t) m.uv_area += uv_area(m.uvs, m.indices, t), m.area3d += area3d(m.positions, m.indices, t);
  if (!(m.uv_area > 0)) throw InputError(file.path, "the UVs of the textured primitives have no area");
  if (lit) add_lit_inputs(file, asset, driving, m);
  return m;
}

bool same_triangles(const LayoutMesh& a, const LayoutMesh& b, double tol) {
  if (a.indices.size() != b.indices.size()) return false;
  for (size_t k = 0; k < a.indices.size(); ++k)
    for (int d = 0; d < 3; ++d)
      if (std::abs(double(a.positions[3 * size_t(a.indices[k]) + size_t(d)]) -
                   b.positions[3 * size_t(b.indices[k]) + size_t(d)]) > tol)
        return false;
  return true;
}

namespace {

// `source` (sampled through ref's UVs) re-baked into target's corresponding triangles.
Image rebake_image(const LayoutMesh& ref, const Image& source, const LayoutMesh& target, uint32_t W, uint32_t H,
                   atlas::RebakeRole role) {
  // Corner-expanded UV arrays: triangle t of `target` is triangle t of `ref`.
  std::vector<float> old_uv(2 * ref.indices.size()), new_uv(2 * ref.indices.size());
  for (size_t k = 0; k < ref.indices.size(); ++k)
    for (int d = 0; d < 2; ++d)
      old_uv[2 * k + size_t(d)] = ref.uvs[2 * size_t(ref.indices[k]) + size_t(d)],
      new_uv[2 * k + size_t(d)] = target.uvs[2 * size_t(target.indices[k]) + size_t(d)];
  std::vector<uint32_t> corners(ref.indices.size());
  std::iota(corners.begin(), corners.end(), 0u);
  atlas::RebakeMesh mesh;
  mesh.indices = corners.data(), mesh.index_count = corners.size();
  mesh.old_uv = old_uv.data(), mesh.new_uv = new_uv.data(), mesh.vertex_count = corners.size();
  atlas::RebakeOptions o;
  o.width = W, o.height = H;
  o.role = role;
  o.wrap_s = o.wrap_t = ref.repeat ? atlas::kWrapRepeat : atlas::kWrapClampToEdge;
  // On a CPU engine (the double-precision oracle) whatever device eval renders on, so a
  // report does not depend on the device; on OpenMP's threads, as eval's own loops.
  engine::EngineOptions eo;
  eo.threads = unsigned(std::max(1, omp_get_max_threads()));
  return atlas::rebake(source, {mesh}, o, *engine::make_cpu_engine(eo));
}

}  // namespace

Image rebake_from(const LayoutMesh& ref, const LayoutMesh& target, uint32_t W, uint32_t H, std::string* method) {
  if (method) *method = "atlas::rebake";
  return rebake_image(ref, ref.full, target, W, H, atlas::RebakeRole::Color);
}

Image rebake_map_from(const LayoutMesh& ref, const MaterialMap& map, const LayoutMesh& target, uint32_t W, uint32_t H) {
  // Normals follow the new UV frame only where the target's tangents come from its UVs
  // (no TANGENT): with stored tangents the frame is the old one and the texels stay data,
  // as reparam re-bakes them.
  const atlas::RebakeRole role =
      map.kind == atlas::RebakeRole::Normal && !target.tangents.empty() ? atlas::RebakeRole::Data : map.kind;
  return rebake_image(ref, map.full, target, W, H, role);
}

std::vector<float> isometric_uvs(const LayoutMesh& ref, double* aspect, nlohmann::ordered_json* info) {
  const Stopwatch t0;
  Mesh welded = atlas::weld_uv_mesh(ref.positions.data(), ref.uvs.data(), ref.positions.size() / 3, ref.indices.data(),
                                    ref.indices.size());
  const atlas::Charts charts = atlas::find_charts(welded);
  const std::vector<atlas::ChartMesh> pieces = atlas::split_charts(welded, charts);
  std::vector<std::vector<double>> chart_uv(charts.count);  // per chart vertex, 3-D area scale
  size_t flattened = 0, kept = 0;
  for (uint32_t c = 0; c < charts.count; ++c) {
    const atlas::ChartMesh& piece = pieces[c];
    double a3 = 0, a2 = 0;
    for (uint32_t t : piece.triangles) a3 += area3d(ref.positions, ref.indices, t), a2 += uv_area(ref.uvs, ref.indices, t);
    std::vector<double>& cuv = chart_uv[c];
    // The plain solve, not flatten_chart: a chart with holes keeps its input UVs. Filled and
    // flattened, its box holds the holes and the shelves waste them, a weaker baseline
    // (measured: Duck's UV area 0.66 -> 0.50 of the square, Fox's 0.42 -> 0.34 and its pixel
    // ratio against the input 1.10 -> 1.30).
    try {
      flatten::Options o;
      o.max_iterations = 300;
      auto r = flatten::flatten(atlas::chart_surface(welded, piece), o);
      // A failed solve, flips or non-finite UVs: fall back to the input UVs like a non-disk.
      if (const std::string why = flatten::invalid_reason(r); !why.empty()) throw flatten::FlattenError(why);
      cuv = r.uv;
      ++flattened;
    } catch (const flatten::FlattenError&) {
      // Not a disk (or unusable): the input UVs at the 3-D area scale.
      const double s = a2 > 0 ? std::sqrt(a3 / a2) : 1.0;
      cuv.resize(2 * piece.uv_vertices.size());
      for (size_t i = 0; i < piece.uv_vertices.size(); ++i)
        for (size_t d = 0; d < 2; ++d) cuv[2 * i + d] = welded.uvs[2 * size_t(piece.uv_vertices[i]) + d] * s;
      ++kept;
    }
  }
  // Shelves at one scale, then the atlas stretched to the unit square.
  std::vector<std::vector<double>*> shelved;
  for (auto& cuv : chart_uv) shelved.push_back(&cuv);
  const auto [used_w, used_h] = atlas::shelve_charts(shelved);
  std::vector<double> uv(2 * welded.uv_count(), 0.0);  // per welded UV vertex
  for (uint32_t c = 0; c < charts.count; ++c)
    for (size_t i = 0; i < pieces[c].uv_vertices.size(); ++i) {
      const size_t u = pieces[c].uv_vertices[i];
      uv[2 * u] = chart_uv[c][2 * i] / used_w, uv[2 * u + 1] = chart_uv[c][2 * i + 1] / used_h;
    }
  *aspect = used_w / used_h;
  // Back to the layout's vertices (a vertex's welded UV vertex is the same in every corner).
  std::vector<float> out(ref.uvs.size(), 0.0f);
  for (size_t k = 0; k < ref.indices.size(); ++k)
    for (int d = 0; d < 2; ++d)
      out[2 * size_t(ref.indices[k]) + size_t(d)] = float(uv[2 * size_t(welded.uv_triangles[k]) + size_t(d)]);
  if (info)
    *info = {{"charts", charts.count},
             {"flattened", flattened},
             {"kept_input_uvs", kept},
             {"seconds", t0.seconds()}};
  return out;
}

}  // namespace uvpress::eval::detail
