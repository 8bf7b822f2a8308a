#include "pipeline/reparam.h"

#include "atlas/charts.h"
#include "atlas/pack.h"
#include "atlas/rebake.h"
#include "core/error.h"
#include "core/quantile.h"
#include "eval/eval.h"
#include "io/asset.h"
#include "io/gltf_append.h"
#include "io/image_io.h"
#include "perceptual/mesh_stage.h"
#include "perceptual/triangle_view.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>
#include <set>

namespace uvpress::pipeline {

using json = nlohmann::ordered_json;

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

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
  size_t optimized = 0, feasible = 0, resolved = 0, sampled = 0, coarsened = 0;
  std::vector<double> infeasible_identity_gmsd, lambda_area;

  json to_json(const perceptual::TriangleStageOptions& t) const {
    json j = {{"epsilon", t.epsilon},
              {"evaluations", t.evaluations},
              {"early_stop", t.early_stop},
              {"view_size", t.view_size},
              {"triangles", optimized},
              {"feasible", feasible},
              {"infeasible", optimized - feasible},
              {"views_resolve_texels", resolved},
              {"sampled_by_patches", sampled},
              {"tiles_coarsened", coarsened},
              {"lambda_area_quartiles",
               {quantile(lambda_area, 0.25), quantile(lambda_area, 0.5), quantile(lambda_area, 0.75)}}};
    if (!infeasible_identity_gmsd.empty())
      j["infeasible_identity_gmsd"] = {{"median", quantile(infeasible_identity_gmsd, 0.5)},
                                       {"max", quantile(infeasible_identity_gmsd, 1.0)}};
    return j;
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
  std::vector<double> new_uv;         // after the mesh stage, same units
  bool rigid = false;                 // mixed orientation (folded / partly mirrored): not optimized
};

double signed_area(const double* a, const double* b, const double* c) {
  return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
}

std::string format_of(const std::vector<uint8_t>& bytes) {
  std::string f = io::sniff_image_format(bytes.data(), bytes.size());
  return f == "jpeg" ? "jpeg" : "png";
}

bool has_tangents(const tinygltf::Model& m, const io::Primitive& p) {
  return m.meshes[size_t(p.mesh)].primitives[size_t(p.primitive)].attributes.count("TANGENT") > 0;
}

}  // namespace

json reparam(io::GltfFile& file, engine::Engine& engine, const ReparamOptions& o, const Progress& progress) {
  const auto t_start = Clock::now();
  const io::GltfFile original = o.max_gmsd > 0 ? file : io::GltfFile{};
  json report;
  json stages = json::object();
  json warnings = json::array();
  io::Asset asset = io::build_asset(file);
  std::vector<Layout> layouts = find_layouts(asset);
  auto device = engine.device();
  report["device"] = device.name;
  report["backend"] = device.backend;

  size_t flips = 0, total_charts = 0, optimized = 0, infeasible = 0;
  double old_texels = 0, new_texels = 0;
  json textures = json::array(), layout_reports = json::array();
  double t_triangle = 0, t_mesh = 0, t_pack = 0, t_bake = 0;

  for (size_t li = 0; li < layouts.size(); ++li) {
    Layout& L = layouts[li];
    json jl = {{"images", L.images}, {"driver", L.driver}};
    json sets = json::array();
    for (auto& s : L.uv_sets) sets.push_back({{"mesh", asset.primitives[size_t(s.primitive)].mesh},
                                              {"primitive", asset.primitives[size_t(s.primitive)].primitive},
                                              {"tex_coord", s.tex_coord}});
    jl["uv_sets"] = sets;
    if (!L.untouched.empty()) {
      jl["untouched"] = L.untouched;
      warnings.push_back("layout " + std::to_string(li) + " left untouched: " + L.untouched);
      layout_reports.push_back(jl);
      continue;
    }
    const std::string driver_name = file.path + ": image " + std::to_string(L.driver);
    Image driver = io::decode_image(file.image_bytes[size_t(L.driver)], driver_name);
    const double W = driver.width, H = driver.height;
    std::vector<float> luminance = perceptual::luminance_plane(driver);

    // Charts of every UV set, with the triangle stage's targets.
    std::vector<Chart> charts;
    std::vector<std::vector<uint32_t>> welded_of_vertex(L.uv_sets.size());  // primitive vertex -> welded UV id
    std::vector<size_t> welded_count(L.uv_sets.size());
    std::vector<std::vector<perceptual::TriangleTarget>> chart_targets(L.uv_sets.size());
    double old_used = 0;  // eq. 20: source texels under the input's charts
    size_t layout_flips = 0, rigid = 0, mesh_failed = 0;
    TriangleCounts tri;
    for (size_t si = 0; si < L.uv_sets.size(); ++si) {
      const io::Primitive& prim = asset.primitives[size_t(L.uv_sets[si].primitive)];
      const std::vector<float>& uv = prim.uv_sets[size_t(L.uv_sets[si].tex_coord)].uv;
      Mesh welded = atlas::weld_uv_mesh(prim.positions.data(), uv.data(), prim.vertex_count(), prim.indices.data(),
                                        prim.indices.size());
      welded_count[si] = welded.uv_count();
      welded_of_vertex[si].assign(prim.vertex_count(), UINT32_MAX);
      for (size_t c = 0; c < prim.indices.size(); ++c) welded_of_vertex[si][prim.indices[c]] = welded.uv_triangles[c];
      atlas::Charts found = atlas::find_charts(welded);

      // Triangle stage (or identity targets when not optimizing).
      std::vector<perceptual::TriangleTarget> targets(prim.triangle_count());
      if (o.optimize && prim.triangle_count() > 0) {
        auto t0 = Clock::now();
        perceptual::TriangleViewInput in{prim.positions.data(), prim.vertex_count(), prim.indices.data(),
                                         prim.triangle_count(), uv.data(), driver.width, driver.height};
        perceptual::TriangleStageOptions topt = o.triangle;
        if (progress) {
          const std::string stage = "triangles (layout " + std::to_string(li) + ")";
          topt.progress = [&progress, stage](size_t done, size_t total) { progress(stage, done, total); };
        }
        auto results = perceptual::optimize_triangles(engine, in, luminance, topt);
        for (size_t t = 0; t < results.size(); ++t) {
          const auto& r = results[t];
          targets[t] = {r.rotation, r.stretch, r.weight_rotation, r.weight_stretch};
          tri.optimized += 1;
          tri.feasible += r.feasible;
          if (!r.feasible) tri.infeasible_identity_gmsd.push_back(r.identity_gmsd);
          tri.resolved += r.texels_per_pixel <= 1.0 + 1e-6;
          tri.sampled += !r.complete;
          tri.coarsened += r.identity_lattice > 1;
          tri.lambda_area.push_back(r.lambda1 * r.lambda2);
        }
        t_triangle += seconds_since(t0);
      }
      chart_targets[si] = std::move(targets);

      const size_t first_chart = charts.size();
      charts.resize(first_chart + found.count);
      for (size_t t = 0; t < prim.triangle_count(); ++t) charts[first_chart + found.chart_of_triangle[t]].triangles.push_back(uint32_t(t));
      for (size_t c = first_chart; c < charts.size(); ++c) {
        Chart& ch = charts[c];
        ch.uv_set = si;
        std::map<uint32_t, uint32_t> local_of;
        for (uint32_t t : ch.triangles)
          for (int k = 0; k < 3; ++k) {
            uint32_t w = welded.uv_triangles[3 * t + uint32_t(k)];
            auto [it, fresh] = local_of.emplace(w, uint32_t(ch.vertices.size()));
            if (fresh) {
              ch.vertices.push_back(w);
              ch.uv.push_back(welded.uvs[2 * w] * W);
              ch.uv.push_back(welded.uvs[2 * w + 1] * H);
            }
            ch.local.push_back(it->second);
          }
        // Orientation: all triangles one way (a mirrored chart is flipped consistently);
        // mixed orientations mean folds or overlaps in UV, kept rigid.
        size_t positive = 0, negative = 0;
        for (size_t t = 0; t < ch.triangles.size(); ++t) {
          double a = signed_area(&ch.uv[2 * ch.local[3 * t]], &ch.uv[2 * ch.local[3 * t + 1]], &ch.uv[2 * ch.local[3 * t + 2]]);
          old_used += std::abs(a);
          positive += a > 0, negative += a < 0;
        }
        if (negative > positive)
          for (size_t t = 0; t < ch.triangles.size(); ++t) std::swap(ch.local[3 * t + 1], ch.local[3 * t + 2]);
        ch.rigid = positive > 0 && negative > 0;
        rigid += ch.rigid;
      }
    }

    // Mesh stage per chart. Weights floored relative to the whole layout's mean (not only
    // the chart's): a chart of flat signal has weights near 0 everywhere and would follow
    // its targets only at w / (w + w_rs) per iteration.
    auto t0 = Clock::now();
    perceptual::MeshStageOptions mesh_options;
    {
      double sum = 0;
      size_t n = 0;
      for (const auto& set : chart_targets)
        for (const auto& t : set)
          if (std::isfinite(t.weight_rotation) && std::isfinite(t.weight_stretch))
            sum += t.weight_rotation + t.weight_stretch, n += 2;
      mesh_options.weight_floor = n ? 1e-3 * sum / double(n) : 0;
    }
    for (size_t c = 0; c < charts.size(); ++c) {
      Chart& ch = charts[c];
      if (!o.optimize || ch.rigid) {
        ch.new_uv = ch.uv;
        continue;
      }
      std::vector<perceptual::TriangleTarget> targets;
      targets.reserve(ch.triangles.size());
      for (uint32_t t : ch.triangles) targets.push_back(chart_targets[ch.uv_set][t]);
      perceptual::MeshStageResult fit = perceptual::fit_chart(ch.uv, ch.local, targets, mesh_options);
      ch.new_uv = std::move(fit.uv);
      // A failed factorization leaves the chart at its input (or last accepted, flip-free)
      // shape: said in the report and as a warning, never passed off as optimized.
      if (fit.failed()) {
        ++mesh_failed;
        if (mesh_failed == 1) warnings.push_back("layout " + std::to_string(li) + " chart " + std::to_string(c) + ": mesh stage " + fit.failure);
      }
      if (progress) progress("mesh stage (layout " + std::to_string(li) + ")", c + 1, charts.size());
    }
    // No triangle may flip relative to the input.
    for (const Chart& ch : charts)
      for (size_t t = 0; t < ch.triangles.size(); ++t) {
        const uint32_t* l = &ch.local[3 * t];
        double before = signed_area(&ch.uv[2 * l[0]], &ch.uv[2 * l[1]], &ch.uv[2 * l[2]]);
        double after = signed_area(&ch.new_uv[2 * l[0]], &ch.new_uv[2 * l[1]], &ch.new_uv[2 * l[2]]);
        if ((before > 0 && after <= 0) || (before < 0 && after >= 0)) ++layout_flips;
      }
    t_mesh += seconds_since(t0);

    // Pack into the budget (eq. 20-21), never above the source texel density.
    t0 = Clock::now();
    std::vector<atlas::ChartShape> shapes(charts.size());
    for (size_t c = 0; c < charts.size(); ++c) shapes[c] = {charts[c].new_uv, charts[c].local};
    atlas::BudgetOptions budget;
    budget.cost = o.max_gmsd > 0 ? 1.0 : o.cost, budget.size = o.max_gmsd > 0 ? 0 : o.size;
    budget.pot = o.power_of_two;
    budget.measure = atlas::CostMeasure::ImageTexels;  // --cost is about texture memory
    budget.pack.gutter = o.gutter, budget.pack.block = o.block;
    atlas::AtlasChoice choice = atlas::choose_atlas(shapes, driver.width, driver.height, old_used, budget);
    if (!choice.packing.ok)
      throw InputError(file.path, "the charts of layout " + std::to_string(li) + " do not fit any atlas within the budget");
    const auto& packing = choice.packing;
    // New UVs per primitive vertex (vertices no triangle uses keep theirs).
    std::vector<std::vector<float>> new_uv(L.uv_sets.size()), welded_new(L.uv_sets.size());
    for (size_t si = 0; si < L.uv_sets.size(); ++si) welded_new[si].assign(2 * welded_count[si], 0.0f);
    for (size_t c = 0; c < charts.size(); ++c)
      for (size_t v = 0; v < charts[c].vertices.size(); ++v) {
        auto uv = packing.map_uv(c, charts[c].new_uv[2 * v], charts[c].new_uv[2 * v + 1]);
        welded_new[charts[c].uv_set][2 * charts[c].vertices[v]] = float(uv[0]);
        welded_new[charts[c].uv_set][2 * charts[c].vertices[v] + 1] = float(uv[1]);
      }
    for (size_t si = 0; si < L.uv_sets.size(); ++si) {
      const io::Primitive& prim = asset.primitives[size_t(L.uv_sets[si].primitive)];
      new_uv[si] = prim.uv_sets[size_t(L.uv_sets[si].tex_coord)].uv;
      for (size_t v = 0; v < prim.vertex_count(); ++v) {
        uint32_t w = welded_of_vertex[si][v];
        if (w == UINT32_MAX) continue;
        new_uv[si][2 * v] = welded_new[si][2 * w], new_uv[si][2 * v + 1] = welded_new[si][2 * w + 1];
      }
    }
    t_pack += seconds_since(t0);

    // Re-bake every image of the layout into the new UVs, at the driver's new density.
    t0 = Clock::now();
    std::vector<atlas::RebakeMesh> meshes;
    for (size_t si = 0; si < L.uv_sets.size(); ++si) {
      const io::Primitive& prim = asset.primitives[size_t(L.uv_sets[si].primitive)];
      meshes.push_back({prim.indices.data(), prim.indices.size(), prim.uv_sets[size_t(L.uv_sets[si].tex_coord)].uv.data(),
                        new_uv[si].data(), prim.vertex_count()});
    }
    size_t baked_count = 0;
    for (int i : L.images) {
      const io::AssetImage& img = asset.images[size_t(i)];
      const std::string name = file.path + ": image " + std::to_string(i);
      Image source = i == L.driver ? driver : io::decode_image(file.image_bytes[size_t(i)], name);
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
      Image baked = atlas::rebake(source, meshes, ro, nullptr, &engine);
      const std::vector<uint8_t> old_bytes = file.image_bytes[size_t(i)];
      file.image_bytes[size_t(i)] = io::encode_image(baked, format_of(old_bytes));
      old_texels += double(source.width) * source.height;
      new_texels += double(baked.width) * baked.height;
      textures.push_back({{"image", i},
                          {"name", img.name},
                          {"role", img.uses.empty() ? "other" : io::to_string(img.uses.front().role)},
                          {"old_size", {source.width, source.height}},
                          {"new_size", {baked.width, baked.height}},
                          {"old_bytes", old_bytes.size()},
                          {"new_bytes", file.image_bytes[size_t(i)].size()}});
      if (progress) progress("re-bake (layout " + std::to_string(li) + ")", ++baked_count, L.images.size());
    }
    t_bake += seconds_since(t0);

    // New UV accessors (the old ones may be shared with primitives outside the layout).
    for (size_t si = 0; si < L.uv_sets.size(); ++si) {
      const io::Primitive& prim = asset.primitives[size_t(L.uv_sets[si].primitive)];
      auto& gp = file.model.meshes[size_t(prim.mesh)].primitives[size_t(prim.primitive)];
      gp.attributes["TEXCOORD_" + std::to_string(L.uv_sets[si].tex_coord)] = io::append_float_accessor(file.model, new_uv[si], TINYGLTF_TYPE_VEC2);
    }
    flips += layout_flips;
    total_charts += charts.size();
    jl["charts"] = charts.size();
    jl["rigid_charts"] = rigid;
    jl["atlas"] = {packing.width, packing.height};
    jl["scale"] = packing.scale;
    jl["packing_efficiency"] = packing.efficiency;
    jl["chart_cost_ratio"] = choice.cost_ratio;
    jl["flips"] = layout_flips;
    if (o.optimize) {
      jl["mesh_stage_failed_charts"] = mesh_failed;
      if (mesh_failed > 1) warnings.push_back("layout " + std::to_string(li) + ": the mesh stage failed on " + std::to_string(mesh_failed) + " charts (kept unreshaped)");
      jl["triangle_stage"] = tri.to_json(o.triangle);
      infeasible += tri.optimized - tri.feasible, optimized += tri.optimized;
    }
    layout_reports.push_back(jl);
  }

  if (o.max_gmsd > 0 && !textures.empty()) {
    // --max-gmsd: the cheapest point of the new layout's q-c curve that meets the bound.
    auto t0 = Clock::now();
    eval::EvalOptions eo;
    eo.resolution = 256;
    eo.artifacts = false;
    eo.cost_grid = {0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0};
    json ev = eval::evaluate(original, {{"reparam", &file}}, engine, eo, nullptr,
                             progress ? eval::Progress(progress) : eval::Progress());
    const json& layout = ev["layouts"][1];
    // eval's sizes are image texels relative to the input's image: the point's width is the
    // size to write, whatever the packing made of the written image.
    const double full_w = layout["as_written"]["width"].get<double>();
    double ratio = 1, chosen_q = layout["curve"].back()["q"].get<double>(), chosen_c = 1;
    bool met = false;
    for (const auto& point : layout["curve"])
      if (point["q"].get<double>() <= o.max_gmsd) {
        ratio = std::min(1.0, point["width"].get<double>() / full_w);
        chosen_q = point["q"].get<double>(), chosen_c = point["c_r"].get<double>();
        met = true;
        break;
      }
    if (!met) warnings.push_back("no size meets --max-gmsd " + std::to_string(o.max_gmsd) + "; kept the source density");
    new_texels = 0;
    for (auto& t : textures) {
      const int i = t["image"].get<int>();
      Image img = io::decode_image(file.image_bytes[size_t(i)], file.path);
      const uint32_t w = std::max(1u, uint32_t(std::lround(img.width * ratio)));
      const uint32_t h = std::max(1u, uint32_t(std::lround(img.height * ratio)));
      if (w != img.width || h != img.height) {
        const std::string format = format_of(file.image_bytes[size_t(i)]);
        file.image_bytes[size_t(i)] = io::encode_image(eval::resize_area(img, w, h), format);
      }
      t["new_size"] = {w, h};
      t["new_bytes"] = file.image_bytes[size_t(i)].size();
      new_texels += double(w) * h;
    }
    report["max_gmsd"] = {{"bound", o.max_gmsd}, {"met", met}, {"c_r", chosen_c}, {"q", chosen_q}, {"scale", ratio}};
    stages["max_gmsd_eval"] = seconds_since(t0);
  }

  stages["triangle_stage"] = t_triangle;
  stages["mesh_stage"] = t_mesh;
  stages["pack"] = t_pack;
  stages["rebake"] = t_bake;
  report["layouts"] = layout_reports;
  report["textures"] = textures;
  report["cost_ratio"] = old_texels > 0 ? new_texels / old_texels : 1.0;
  report["flips"] = flips;
  report["charts"] = total_charts;
  report["triangles_optimized"] = optimized;
  report["triangles_infeasible"] = infeasible;
  report["stages"] = stages;
  report["warnings"] = warnings;
  report["seconds"] = seconds_since(t_start);
  return report;
}

}  // namespace uvpress::pipeline
