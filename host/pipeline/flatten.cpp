#include "pipeline/flatten.h"

#include "atlas/charts.h"
#include "atlas/uv_overlap.h"
#include "core/error.h"
#include "flatten/report.h"
#include "io/asset.h"
#include "io/gltf_append.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>

namespace uvpress::pipeline {

namespace {

// Uniformly scales and translates 2-D points (2 per vertex) into [0,1]^2.
void normalize_unit_square(std::vector<double>& uv) {
  if (uv.empty()) return;
  double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
  for (size_t i = 0; i < uv.size(); ++i) lo[i % 2] = std::min(lo[i % 2], uv[i]), hi[i % 2] = std::max(hi[i % 2], uv[i]);
  const double extent = std::max(hi[0] - lo[0], hi[1] - lo[1]);
  const double s = extent > 0 ? 1 / extent : 1;
  for (size_t i = 0; i < uv.size(); ++i) uv[i] = (uv[i] - lo[i % 2]) * s;
}

// The value an OBJ reader gets back from "%.9g".
double as_written_obj(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return std::strtod(buf, nullptr);
}

// Charts of one glTF primitive, as disk meshes indexed by welded UV vertex.
struct PrimitiveCharts {
  Mesh welded;                         // weld_uv_mesh output (uv_triangles = chart vertex ids)
  atlas::Charts charts;
};

// Whether the primitive has a TEXCOORD_0 to chart by (else all UVs read as 0).
bool has_uvs(const io::Primitive& prim) {
  return !prim.uv_sets.empty() && prim.uv_sets[0].uv.size() == 2 * prim.vertex_count();
}

PrimitiveCharts split_primitive(const io::Primitive& prim) {
  PrimitiveCharts pc;
  std::vector<float> zero_uv;
  const float* uv = nullptr;
  if (has_uvs(prim)) {
    uv = prim.uv_sets[0].uv.data();
  } else {
    zero_uv.assign(2 * prim.vertex_count(), 0.0f);
    uv = zero_uv.data();
  }
  pc.welded = atlas::weld_uv_mesh(prim.positions.data(), uv, prim.vertex_count(), prim.indices.data(),
                                  prim.indices.size());
  pc.charts = atlas::find_charts(pc.welded);
  return pc;
}

}  // namespace

FlattenResult flatten_mesh(const Mesh& mesh, const flatten::Options& o, const std::string& input, Mesh& out,
                           const FlattenProgress& progress) {
  FlattenResult result;
  result.method = o.method;
  FlattenedChart chart;
  chart.mesh = mesh;
  // A failed solve (factorization, line search), flipped or non-finite UVs: an error naming
  // the input. A stall at the floor or the iteration limit is a result.
  try {
    chart.result = flatten::flatten(chart.mesh, o);
  } catch (const flatten::FlattenError& e) {
    throw InputError(input, e.what());
  }
  if (std::string why = flatten::invalid_reason(chart.result); !why.empty()) throw InputError(input, why);
  if (progress) progress("flatten");
  out = chart.mesh;
  out.uvs = chart.result.uv;
  normalize_unit_square(out.uvs);
  for (double& x : out.uvs) x = as_written_obj(x);
  out.uv_triangles = out.triangles;
  chart.result.flips = flatten::count_flips(out.triangles, out.uvs);
  result.charts.push_back(std::move(chart));
  return result;
}

FlattenResult flatten_gltf(io::GltfFile& file, const flatten::Options& o, const FlattenProgress& progress,
                           const FlattenWarning& warn) {
  FlattenResult result;
  result.method = o.method;
  result.gltf = true;
  std::vector<FlattenedChart>& charts = result.charts;
  const std::string& input = file.path;
  io::Asset asset = io::build_asset(file);
  if (progress) progress("load");
  if (asset.primitives.empty()) throw InputError(input, "no triangle primitives to flatten");
  struct Placed {
    size_t prim;
    std::vector<uint32_t> welded_uv_vertex;  // chart-local vertex -> welded UV vertex
    size_t chart;                            // index into `charts`
  };
  std::vector<PrimitiveCharts> split;
  std::vector<Placed> placed;
  for (size_t p = 0; p < asset.primitives.size(); ++p) {
    const auto& prim = asset.primitives[p];
    split.push_back(split_primitive(prim));
    const auto& pc = split.back();
    const std::vector<atlas::ChartMesh> pieces = atlas::split_charts(pc.welded, pc.charts);
    for (uint32_t c = 0; c < pc.charts.count; ++c) {
      FlattenedChart chart;
      chart.label = "mesh " + std::to_string(prim.mesh) + " primitive " + std::to_string(prim.primitive) + " chart " +
                    std::to_string(c);
      const std::vector<uint32_t>& back = pieces[c].uv_vertices;
      chart.mesh = atlas::chart_surface(pc.welded, pieces[c]);
      // Holes filled virtually (fan to a temporary centroid vertex per extra boundary loop),
      // dropped after the solve. A chart that still cannot be flattened (non-manifold, a
      // handle, a degenerate Tutte embedding) keeps its input UVs, scaled into its shelf,
      // with a warning naming it.
      std::vector<double> input_uv(2 * back.size());
      for (size_t i = 0; i < back.size(); ++i)
        for (int d = 0; d < 2; ++d) input_uv[2 * i + size_t(d)] = pc.welded.uvs[2 * size_t(back[i]) + size_t(d)];
      auto keep_input = [&](const std::string& why) {
        chart.skipped = why;
        chart.result = flatten::Result();
        chart.result.uv = input_uv;
        if (warn) warn(chart.label + ": skipped: " + why + " (input UVs kept)");
      };
      try {
        flatten::ChartResult flat = flatten::flatten_chart(chart.mesh, o);
        chart.result = std::move(flat.result);
        chart.filled_holes = flat.filled_holes;
      } catch (const flatten::FlattenError& e) {
        keep_input(e.what());
      }
      if (chart.skipped.empty()) {
        // A failed solve on a disk is a failure, not a skip: exit 1, nothing written.
        if (std::string why = flatten::invalid_reason(chart.result); !why.empty())
          throw InputError(input, chart.label + ": " + why);
        // Flip-free is not injective: a free boundary can run over itself. Such a chart
        // keeps its input UVs when it has some (without, there is no shape to keep).
        const auto overlaps = atlas::find_new_overlaps(input_uv.data(), chart.result.uv.data(),
                                                       chart.mesh.triangles.data(), chart.mesh.triangle_count());
        if (!overlaps.empty()) {
          const std::string why = "the flattened chart runs over itself (" + std::to_string(overlaps.size()) +
                                  " pairs of triangles overlap)";
          if (!has_uvs(prim)) throw InputError(input, chart.label + ": " + why + " and there are no input UVs to keep");
          keep_input(why);
        }
      }
      placed.push_back({p, back, charts.size()});
      charts.push_back(std::move(chart));
    }
  }
  if (progress) progress("flatten");

  // Shelf layout at one common scale (UV area = 3-D area; atlas::shelve_charts).
  std::vector<std::vector<double>> chart_uv;
  std::vector<std::vector<double>*> shelved;
  for (const auto& chart : charts) chart_uv.push_back(chart.result.uv);
  for (auto& uv : chart_uv) shelved.push_back(&uv);
  atlas::shelve_charts(shelved);
  std::vector<double> all;  // every placed UV, for the common normalization
  std::vector<std::vector<double>> welded_uv(split.size());
  for (size_t p = 0; p < split.size(); ++p) welded_uv[p].assign(2 * split[p].welded.uv_count(), 0.0);
  for (const auto& pl : placed) {
    const auto& uv = chart_uv[pl.chart];
    for (size_t i = 0; i < pl.welded_uv_vertex.size(); ++i)
      for (size_t d = 0; d < 2; ++d) welded_uv[pl.prim][2 * size_t(pl.welded_uv_vertex[i]) + d] = uv[2 * i + d];
  }
  for (auto& w : welded_uv) all.insert(all.end(), w.begin(), w.end());
  normalize_unit_square(all);
  size_t offset = 0;
  for (auto& w : welded_uv) std::copy(all.begin() + long(offset), all.begin() + long(offset + w.size()), w.begin()), offset += w.size();

  // Write TEXCOORD_n (n = the first unused set) on every primitive, as float32, and count
  // flips on the float values as written, chart by chart.
  auto& model = file.model;
  if (model.buffers.empty()) model.buffers.emplace_back();
  for (size_t p = 0; p < asset.primitives.size(); ++p) {
    const auto& prim = asset.primitives[p];
    const auto& pc = split[p];
    std::vector<float> uv(2 * prim.vertex_count(), 0.0f);
    for (size_t i = 0; i < prim.indices.size() / 3 * 3; ++i) {
      const uint32_t u = pc.welded.uv_triangles[i];
      uv[2 * size_t(prim.indices[i])] = float(welded_uv[p][2 * size_t(u)]);
      uv[2 * size_t(prim.indices[i]) + 1] = float(welded_uv[p][2 * size_t(u) + 1]);
    }
    for (const auto& pl : placed) {
      if (pl.prim != p) continue;
      std::vector<double> written(2 * pl.welded_uv_vertex.size());
      for (size_t i = 0; i < pl.welded_uv_vertex.size(); ++i)
        for (int d = 0; d < 2; ++d)
          written[2 * i + size_t(d)] = double(float(welded_uv[p][2 * size_t(pl.welded_uv_vertex[i]) + size_t(d)]));
      // A skipped chart's own UVs are what they were: not this tool's flips.
      if (charts[pl.chart].skipped.empty())
        charts[pl.chart].result.flips = flatten::count_flips(charts[pl.chart].mesh.triangles, written);
    }
    const int accessor = io::append_float_accessor(model, uv, TINYGLTF_TYPE_VEC2);
    auto& attributes = model.meshes[size_t(prim.mesh)].primitives[size_t(prim.primitive)].attributes;
    int n = 0;
    while (attributes.count("TEXCOORD_" + std::to_string(n))) ++n;
    attributes["TEXCOORD_" + std::to_string(n)] = accessor;
    if (std::find(result.uv_sets.begin(), result.uv_sets.end(), "TEXCOORD_" + std::to_string(n)) == result.uv_sets.end())
      result.uv_sets.push_back("TEXCOORD_" + std::to_string(n));
  }
  // Injectivity on the values as written, over every primitive at once (they share the
  // unit square): pairs of triangles that overlap in the new set but not in TEXCOORD_0.
  {
    std::vector<double> before, after;
    std::vector<uint32_t> triangles;
    for (size_t p = 0; p < asset.primitives.size(); ++p) {
      const auto& prim = asset.primitives[p];
      const auto& pc = split[p];
      const uint32_t base = uint32_t(before.size() / 2);
      for (size_t u = 0; u < pc.welded.uv_count(); ++u)
        for (int d = 0; d < 2; ++d) {
          before.push_back(pc.welded.uvs[2 * u + size_t(d)]);
          after.push_back(double(float(welded_uv[p][2 * u + size_t(d)])));
        }
      for (size_t i = 0; i < prim.indices.size() / 3 * 3; ++i) triangles.push_back(base + pc.welded.uv_triangles[i]);
    }
    result.overlaps_new = atlas::find_new_overlaps(before.data(), after.data(), triangles.data(), triangles.size() / 3).size();
  }
  return result;
}

FlattenTotals totals(const FlattenResult& result) {
  FlattenTotals t;
  for (const auto& c : result.charts) {
    t.faces += c.mesh.triangle_count(), t.vertices += c.mesh.vertex_count(), t.flips += c.result.flips;
    t.filled_holes += c.filled_holes;
    if (!c.skipped.empty()) {
      ++t.skipped;
      continue;
    }
    t.seconds += c.result.seconds, t.iterations += c.result.iterations;
    t.most_iterations = std::max(t.most_iterations, c.result.iterations), t.eta = std::max(t.eta, c.result.eta);
    t.converged = t.converged && c.result.converged;
    double a3 = 0;
    const auto& m = c.mesh;
    for (size_t i = 0; i < m.triangle_count(); ++i) {
      const double* p0 = &m.positions[3 * size_t(m.triangles[3 * i])];
      const double* p1 = &m.positions[3 * size_t(m.triangles[3 * i + 1])];
      const double* p2 = &m.positions[3 * size_t(m.triangles[3 * i + 2])];
      double e1[3], e2[3];
      for (int k = 0; k < 3; ++k) e1[k] = p1[k] - p0[k], e2[k] = p2[k] - p0[k];
      a3 += 0.5 * std::sqrt(std::pow(e1[1] * e2[2] - e1[2] * e2[1], 2) + std::pow(e1[2] * e2[0] - e1[0] * e2[2], 2) +
                            std::pow(e1[0] * e2[1] - e1[1] * e2[0], 2));
    }
    t.energy += a3 * c.result.energy, t.area += a3;
  }
  return t;
}

nlohmann::ordered_json to_json(const FlattenResult& r, const FlattenFiles& files) {
  const FlattenTotals t = totals(r);
  nlohmann::ordered_json report;
  if (r.charts.size() == 1 && t.skipped == 0 && t.filled_holes == 0) {
    report = flatten::summary_json(r.charts[0].result, r.method, t.faces, t.vertices);
  } else {
    report["method"] = flatten::to_string(r.method);
    report["faces"] = t.faces;
    report["vertices"] = t.vertices;
    report["N_c"] = t.most_iterations;
    report["eta"] = t.eta;
    report["t_c_s"] = t.seconds;
    report["E_c"] = t.area > 0 ? t.energy / t.area : 0.0;
    report["s_per_iter"] = t.iterations ? t.seconds / t.iterations : 0.0;
    report["flips"] = t.flips;
    report["peak_rss_mb"] = flatten::peak_rss_mb();
    report["converged"] = t.converged;
    report["charts"] = nlohmann::ordered_json::array();
    for (const auto& c : r.charts) {
      auto j = flatten::summary_json(c.result, r.method, c.mesh.triangle_count(), c.mesh.vertex_count());
      j["chart"] = c.label;
      if (c.filled_holes) j["filled_holes"] = c.filled_holes;
      if (!c.skipped.empty()) j["skipped"] = c.skipped;
      report["charts"].push_back(j);
    }
  }
  report["input"] = files.input;
  report["output"] = files.output;
  if (r.gltf) {
    report["uv_sets_written"] = r.uv_sets;
    report["charts_skipped"] = t.skipped;
    report["holes_filled"] = t.filled_holes;
    report["overlaps_new"] = r.overlaps_new;
    report["input_validation"] = files.input_validation;
  }
  report["input_bytes"] = files.input_bytes;
  report["output_bytes"] = files.output_bytes;
  return report;
}

AssignResult flatten_assign(io::GltfFile& file, engine::Engine& engine, double cost, const flatten::Options& o,
                            const Progress& progress) {
  ReparamOptions options;
  options.isometric = true, options.flatten = o, options.cost = cost;
  options.optimize = false, options.candidates = false;
  options.guard = false;  // the user asked for these UVs: scored, not replaced by a resize
  AssignResult a;
  a.reparam = reparam(file, engine, options, progress);
  size_t layouts = 0;
  std::set<int> tex_coords;  // the UV sets replaced
  for (const auto& l : a.reparam.layouts) {
    if (!l.isometric) continue;
    ++layouts;
    a.flattened += l.isometric->charts_flattened, a.kept += l.isometric->charts_kept;
    a.holes += l.isometric->holes_filled;
    for (const auto& s : l.uv_sets) tex_coords.insert(s.tex_coord);
  }
  if (layouts == 0) {  // before any warning: one error line
    std::string why;
    for (const auto& l : a.reparam.layouts)
      if (l.untouched) why += (why.empty() ? "" : "; ") + *l.untouched;
    throw InputError(file.path, "--assign: no textured layout to flatten" + (why.empty() ? std::string() : ": " + why));
  }
  for (int t : tex_coords) a.uv_sets += (a.uv_sets.empty() ? "TEXCOORD_" : ", TEXCOORD_") + std::to_string(t);
  // Packed no denser than the source where the input was densest: the ratio comes out below `cost`.
  a.at_density = a.reparam.capped_at_source_density();
  return a;
}

nlohmann::ordered_json to_json(const AssignResult& a, const FlattenFiles& files, double seconds) {
  nlohmann::ordered_json report = {{"input", files.input}, {"output", files.output}, {"assign", true}, {"seconds", seconds},
                                   {"input_bytes", files.input_bytes}, {"output_bytes", files.output_bytes},
                                   {"input_validation", files.input_validation}};
  const nlohmann::ordered_json reparam_report = a.reparam.to_json();  // items() must not outlive it
  for (auto& [key, value] : reparam_report.items())
    if (!report.contains(key)) report[key] = value;
  report["seconds"] = seconds;
  return report;
}

}  // namespace uvpress::pipeline
