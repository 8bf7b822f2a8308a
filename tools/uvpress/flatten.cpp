// uvpress flatten IN -o OUT: foldover-free, low-distortion UVs for a disk-topology mesh by
// the progressive method (or one of its competitors, --method). IN is an OBJ/OFF disk
// mesh, or a glTF asset whose primitives are flattened chart by chart (charts from
// TEXCOORD_0 seams; a primitive without UVs is one chart per connected component). OUT is
// an OBJ with `vt` (the input's own UVs replaced), or a glTF with a new TEXCOORD set on
// every primitive (existing sets untouched). UVs are scaled uniformly into [0,1] (charts
// of a glTF laid out side by side on shelves at one common scale); the tool counts
// flipped triangles on the values as written, and for a glTF the pairs of triangles that
// overlap in the new UVs but did not in TEXCOORD_0 (a flattened chart whose free boundary
// runs over itself keeps its input UVs; any new overlap left fails the run).
//
// --assign (glTF): the materials use the flattened UVs. Each textured layout's charts are
// flattened at one texel density (pipeline/isometric_charts.h), packed into --cost of the
// input's texels, every texture of the layout re-baked into them (never repointed without a
// re-bake) and the UV set the materials sample replaced: reparam's packing, re-bake and
// checks (no new overlaps, no flips), scored on screen against the input.
#include "cli.h"
#include "progress.h"

#include "atlas/charts.h"
#include "atlas/uv_overlap.h"
#include "core/error.h"
#include "flatten/disk_topology.h"
#include "flatten/flatten.h"
#include "flatten/report.h"
#include "io/asset.h"
#include "io/asset_bytes.h"
#include "io/atomic_file.h"
#include "io/gltf_append.h"
#include "io/gltf_io.h"
#include "io/mesh_io.h"
#include "pipeline/reparam.h"
#include "pipeline/texture_costs.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>

namespace uvpress::cli {

namespace {

struct Chart {
  std::string label;
  Mesh mesh;                         // positions + triangles of the chart
  flatten::Result result;
  size_t filled_holes = 0;           // boundary loops closed virtually for the solve
  std::string skipped;               // why the chart kept its input UVs ("" when flattened)
};

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

// A failed solve (factorization, line search), flipped or non-finite UVs: exit 1 naming
// the input, nothing written. A stall at the floor or the iteration limit is a result.
flatten::Result run_chart(const Mesh& mesh, const flatten::Options& o, const std::string& file, const std::string& what) {
  flatten::Result r;
  try {
    r = flatten::flatten(mesh, o);
  } catch (const flatten::FlattenError& e) {
    throw InputError(file, what + e.what());
  }
  if (std::string why = flatten::invalid_reason(r); !why.empty()) throw InputError(file, what + why);
  return r;
}

// Charts of one glTF primitive, as disk meshes indexed by welded UV vertex.
struct PrimitiveCharts {
  Mesh welded;                         // weld_uv_mesh output (uv_triangles = chart vertex ids)
  atlas::Charts charts;
  std::vector<std::vector<uint32_t>> vertex_of;  // per chart: local vertex -> welded UV vertex
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

void flatten_gltf(const Globals& g, const std::string& input, const std::string& output, io::AtomicWriter& writer,
                  const flatten::Options& o,
                  std::vector<Chart>& charts, std::vector<std::string>& uv_sets, size_t& overlaps_new,
                  std::chrono::steady_clock::time_point& t0, nlohmann::ordered_json& checked) {
  io::GltfFile file = g.load_input(input, &checked);
  io::Asset asset = io::build_asset(file);
  g.stage("load", t0);
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
    const size_t nt = pc.welded.triangle_count();
    for (uint32_t c = 0; c < pc.charts.count; ++c) {
      Chart chart;
      chart.label = "mesh " + std::to_string(prim.mesh) + " primitive " + std::to_string(prim.primitive) + " chart " +
                    std::to_string(c);
      std::vector<uint32_t> local(pc.welded.uv_count(), UINT32_MAX), back;
      for (size_t t = 0; t < nt; ++t) {
        if (pc.charts.chart_of_triangle[t] != c) continue;
        for (int k = 0; k < 3; ++k) {
          const uint32_t u = pc.welded.uv_triangles[3 * t + size_t(k)];
          if (local[u] == UINT32_MAX) {
            local[u] = uint32_t(back.size());
            back.push_back(u);
            const uint32_t pv = pc.welded.triangles[3 * t + size_t(k)];
            for (int d = 0; d < 3; ++d) chart.mesh.positions.push_back(pc.welded.positions[3 * size_t(pv) + size_t(d)]);
          }
          chart.mesh.triangles.push_back(local[u]);
        }
      }
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
        std::fprintf(stderr, "uvpress: %s: warning: %s: skipped: %s (input UVs kept)\n", input.c_str(),
                     chart.label.c_str(), why.c_str());
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
      placed.push_back({p, std::move(back), charts.size()});
      charts.push_back(std::move(chart));
    }
  }
  g.stage("flatten", t0);

  // Shelf layout at one common scale (UV area = 3-D area; atlas::shelf_layout).
  struct Box {
    double lo[2], hi[2], x = 0, y = 0;
  };
  std::vector<Box> box(charts.size());
  std::vector<atlas::ShelfBox> shelf(charts.size());
  double total_area = 0;
  for (size_t c = 0; c < charts.size(); ++c) {
    Box& b = box[c];
    b.lo[0] = b.lo[1] = 1e300, b.hi[0] = b.hi[1] = -1e300;
    const auto& uv = charts[c].result.uv;
    for (size_t i = 0; i < uv.size(); ++i) b.lo[i % 2] = std::min(b.lo[i % 2], uv[i]), b.hi[i % 2] = std::max(b.hi[i % 2], uv[i]);
    shelf[c].w = b.hi[0] - b.lo[0], shelf[c].h = b.hi[1] - b.lo[1];
    total_area += shelf[c].w * shelf[c].h;
  }
  atlas::shelf_layout(shelf, 0.01 * std::sqrt(total_area));
  for (size_t c = 0; c < charts.size(); ++c) box[c].x = shelf[c].x, box[c].y = shelf[c].y;
  // Per primitive: the new UV of every glTF vertex.
  std::vector<std::vector<double>> prim_uv(asset.primitives.size());
  for (size_t p = 0; p < asset.primitives.size(); ++p) prim_uv[p].assign(2 * asset.primitives[p].vertex_count(), 0.0);
  std::vector<double> all;  // every placed UV, for the common normalization
  std::vector<std::vector<double>> welded_uv(split.size());
  for (size_t p = 0; p < split.size(); ++p) welded_uv[p].assign(2 * split[p].welded.uv_count(), 0.0);
  for (const auto& pl : placed) {
    const auto& uv = charts[pl.chart].result.uv;
    const Box& b = box[pl.chart];
    for (size_t i = 0; i < pl.welded_uv_vertex.size(); ++i) {
      welded_uv[pl.prim][2 * size_t(pl.welded_uv_vertex[i])] = uv[2 * i] - b.lo[0] + b.x;
      welded_uv[pl.prim][2 * size_t(pl.welded_uv_vertex[i]) + 1] = uv[2 * i + 1] - b.lo[1] + b.y;
    }
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
    if (std::find(uv_sets.begin(), uv_sets.end(), "TEXCOORD_" + std::to_string(n)) == uv_sets.end())
      uv_sets.push_back("TEXCOORD_" + std::to_string(n));
  }
  size_t flips = 0;
  for (const auto& c : charts) flips += c.result.flips;
  if (flips) throw InputError(output, std::to_string(flips) + " flipped triangles in the UVs; nothing written");

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
    overlaps_new = atlas::find_new_overlaps(before.data(), after.data(), triangles.data(), triangles.size() / 3).size();
    if (overlaps_new)
      throw InputError(output, std::to_string(overlaps_new) + " pairs of triangles overlap in the new UVs; nothing written");
  }
  io::save_gltf(file, output, {/*keep_image_names=*/true}, writer);
  g.stage("save", t0);
}

// flatten --assign: the isometric layout through reparam's packing and re-bake, staged in
// `writer`. Returns the report; `summary` gets the line to print once it is committed.
nlohmann::ordered_json assign_gltf(const Globals& g, const std::string& input, const std::string& output, double cost,
                                   const flatten::Options& o, io::AtomicWriter& writer, std::string& summary) {
  const auto t0 = std::chrono::steady_clock::now();
  nlohmann::ordered_json checked;
  io::GltfFile file = g.load_input(input, &checked);
  const io::AssetBytes in_files = io::asset_bytes(input, g.refs());
  const nlohmann::ordered_json old_costs = pipeline::image_costs(file)["totals"];
  auto engine = g.make_engine();
  pipeline::ReparamOptions options;
  options.isometric = true, options.flatten = o, options.cost = cost;
  options.optimize = false, options.candidates = false;
  options.guard = false;  // the user asked for these UVs: scored, not replaced by a resize
  ProgressDisplay progress(g.verbose);
  nlohmann::ordered_json r = pipeline::reparam(file, *engine, options, std::ref(progress)).to_json();
  progress.finish();
  size_t flattened = 0, kept = 0, holes = 0, layouts = 0;
  std::set<int> tex_coords;  // the UV sets replaced
  for (const auto& l : r["layouts"]) {
    if (!l.contains("isometric")) continue;
    ++layouts;
    flattened += l["isometric"]["charts_flattened"].get<size_t>(), kept += l["isometric"]["charts_kept"].get<size_t>();
    holes += l["isometric"]["holes_filled"].get<size_t>();
    for (const auto& s : l["uv_sets"]) tex_coords.insert(s["tex_coord"].get<int>());
  }
  if (layouts == 0) {  // before any warning: one error line
    std::string why;
    for (const auto& l : r["layouts"])
      if (l.contains("untouched")) why += (why.empty() ? "" : "; ") + l["untouched"].get<std::string>();
    throw InputError(input, "--assign: no textured layout to flatten" + (why.empty() ? std::string() : ": " + why));
  }
  std::string sets;
  for (int t : tex_coords) sets += (sets.empty() ? "TEXCOORD_" : ", TEXCOORD_") + std::to_string(t);
  io::save_gltf(file, output, {/*keep_image_names=*/true}, writer);
  const io::AssetBytes out_files = io::staged_asset_bytes(writer, output);
  for (const auto& w : r["warnings"]) std::fprintf(stderr, "uvpress: %s: warning: %s\n", input.c_str(), w.get<std::string>().c_str());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  nlohmann::ordered_json report = {{"input", input}, {"output", output}, {"assign", true}, {"seconds", seconds},
                                   {"input_bytes", in_files.total()}, {"output_bytes", out_files.total()},
                                   {"input_validation", checked}};
  for (auto& [key, value] : r.items())
    if (!report.contains(key)) report[key] = value;
  report["seconds"] = seconds;
  const nlohmann::ordered_json new_costs = pipeline::image_costs(file)["totals"];
  // Packed no denser than the source where the input was densest: the ratio comes out below --cost.
  bool at_density = false;
  for (const auto& l : r["layouts"]) at_density |= l.value("capped_at_source_density", false);
  char cost_text[96];
  std::snprintf(cost_text, sizeof cost_text, "cost ratio %.3f%s", r["cost_ratio"].get<double>(),
                at_density && r["cost_ratio"].get<double>() < 0.98 * cost ? " (capped at the source texel density)" : "");
  std::string quality = "not scored on screen";
  if (r["q"].is_number()) {
    char text[96];
    std::snprintf(text, sizeof text, "on screen q %.3g against the input", r["q"].get<double>());
    quality = text;
  }
  char line[2048];
  std::snprintf(line, sizeof line, "%s (%s, %llu texels) -> %s (%s, %llu texels): %zu charts flattened%s%s, textures re-baked into %s, %s, "
              "%s, %.1f s",
              input.c_str(), human_bytes(in_files.total()).c_str(), (unsigned long long)old_costs["texels"].get<uint64_t>(),
              output.c_str(), human_bytes(out_files.total()).c_str(), (unsigned long long)new_costs["texels"].get<uint64_t>(),
              flattened, kept ? (", " + std::to_string(kept) + " kept their UVs").c_str() : "",
              holes ? (", " + std::to_string(holes) + " holes filled for the solve").c_str() : "", sets.c_str(),
              cost_text, quality.c_str(), seconds);
  summary = line;
  return report;
}

// An OBJ keeps its materials (mtllib, usemtl) and normals (vn); `note` says what the
// rewrite changed besides: the input's own UVs replaced, group lines not kept.
void flatten_mesh(const Globals& g, const std::string& input, const std::string& output, io::AtomicWriter& writer,
                  const flatten::Options& o,
                  std::vector<Chart>& charts, std::chrono::steady_clock::time_point& t0, std::string& note) {
  Chart chart;
  io::ObjExtras extras;
  chart.mesh = io::read_mesh(input, &extras);
  if (chart.mesh.has_uvs()) note += ", the input's UVs (vt) replaced";
  if (extras.dropped) note += ", " + std::to_string(extras.dropped) + " o/g/s lines not kept";
  g.stage("load", t0);
  chart.result = run_chart(chart.mesh, o, input, "");
  g.stage("flatten", t0);
  Mesh out = chart.mesh;
  out.uvs = chart.result.uv;
  normalize_unit_square(out.uvs);
  for (double& x : out.uvs) x = as_written_obj(x);
  out.uv_triangles = out.triangles;
  chart.result.flips = flatten::count_flips(out.triangles, out.uvs);
  if (chart.result.flips)
    throw InputError(output, std::to_string(chart.result.flips) + " flipped triangles in the UVs; nothing written");
  io::write_obj(out, output, &extras, writer);
  g.stage("save", t0);
  charts.push_back(std::move(chart));
}

}  // namespace

void add_flatten(CLI::App& app, Globals& g) {
  auto* cmd = app.add_subcommand("flatten", "Foldover-free low-distortion UVs for disk meshes (progressive parameterization)");
  struct Args {
    std::string input, output, method = "progressive", log;
    int max_iterations = 5000;
    double bound = 60;
    int break_factorization = 0;
    bool assign = false;
    double cost = 1.0;
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("input", a->input, "Disk mesh (.obj, .off) or glTF asset (.gltf, .glb)")->required();
  cmd->add_option("-o,--output", a->output, "Output: .obj (with vt), or .gltf/.glb (new TEXCOORD set)")->required();
  cmd->add_option("--method", a->method, "progressive | slim | cm | p-cm | hybrid")
      ->capture_default_str()
      ->check(CLI::IsMember({"progressive", "slim", "cm", "p-cm", "hybrid"}));
  cmd->add_option("--log", a->log, "Per-iteration log: FILE.csv or FILE.json");
  cmd->add_option("--max-iter", a->max_iterations, "Iteration limit")->capture_default_str()->check(CLI::Range(1, 1000000));
  cmd->add_option("--bound", a->bound, "Distortion bound K of the progressive references")
      ->capture_default_str()
      ->check(CLI::Range(1.0001, 1e12));
  cmd->add_flag("--assign", a->assign,
                "glTF: the materials use the flattened UVs: every textured layout's charts flattened at one texel "
                "density, packed and its textures re-baked into them (replacing the UV set they sample)");
  cmd->add_option("--cost", a->cost, "With --assign: texels of the re-baked textures relative to the input's")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 1.0));
  // Test hook, not in --help: the N-th numeric factorization fails (not positive definite).
  cmd->add_option("--test-break-factorization", a->break_factorization)->group("");
  cmd->callback([&g, a] {
    g.action = [&g, a] {
      auto t0 = std::chrono::steady_clock::now();
      const std::string in_ext = io::extension_of(a->input), out_ext = io::extension_of(a->output);
      const bool gltf_in = in_ext == ".gltf" || in_ext == ".glb";
      if (!gltf_in && in_ext != ".obj" && in_ext != ".off") {
        io::read_file(a->input);  // a missing file says so first
        throw InputError(a->input, "unsupported input format '" + in_ext + "' (use .obj, .off, .gltf or .glb)");
      }
      if (out_ext != ".obj" && !io::is_gltf_output_path(a->output))
        throw InputError(a->output, "unsupported output format (use .obj, .gltf or .glb)");
      if (!gltf_in && out_ext != ".obj")
        throw InputError(a->output, "an OBJ/OFF input is written as .obj (glTF output needs a glTF input)");
      if (gltf_in && out_ext == ".obj")
        throw InputError(a->output, "a glTF input is written as .gltf or .glb");
      if (a->assign && !gltf_in) throw InputError(a->input, "--assign needs a glTF input (its materials use the new UVs)");
      if (a->assign && !a->log.empty()) throw InputError(a->log, "--log is not written with --assign (see --report)");
      const std::string log_ext = io::extension_of(a->log);
      if (!a->log.empty() && log_ext != ".csv" && log_ext != ".json")
        throw InputError(a->log, "--log must name a .csv or .json file");
      g.prepare_outputs({a->output, a->log});

      flatten::Options o;
      o.method = *flatten::parse_method(a->method);
      o.max_iterations = a->max_iterations;
      o.K = a->bound;
      o.test_break_factorization = a->break_factorization;
      if (g.verbose)
        o.on_iteration = [](const flatten::IterationRecord& r) {
          std::fprintf(stderr, "iter %3d %-6s E %.9f  e_n %.2e  max D %.4g  D<=K %.4f  t %.4f  step %.3g  %.3f s\n",
                       r.iteration, r.phase, r.energy, r.relative_change, r.max_distortion, r.fraction_bounded,
                       r.t_com, r.step, r.t_total);
        };
      flatten::reset_peak_rss();
      std::vector<Chart> charts;
      std::vector<std::string> uv_sets;  // glTF: the TEXCOORD sets written
      size_t overlaps_new = 0;           // glTF: always 0 when written
      std::string mesh_note;             // OBJ/OFF: what the rewrite changed besides the UVs
      // The output and its report (and --log) appear together: one that cannot be written
      // leaves none of them.
      io::AtomicWriter writer;
      if (a->assign) {
        std::string summary;
        const auto report = assign_gltf(g, a->input, a->output, a->cost, o, writer, summary);
        g.write_report(report, writer);
        writer.commit();
        std::printf("%s\n", summary.c_str());
        return 0;
      }
      nlohmann::ordered_json checked;    // glTF: the input's validation on load
      if (gltf_in) flatten_gltf(g, a->input, a->output, writer, o, charts, uv_sets, overlaps_new, t0, checked);
      else flatten_mesh(g, a->input, a->output, writer, o, charts, t0, mesh_note);

      if (!a->log.empty()) {
        std::vector<flatten::LabelledLog> logs;
        for (const auto& c : charts) logs.push_back({c.label, &c.result.log});
        writer.add(a->log, log_ext == ".csv" ? flatten::log_csv(logs) : flatten::log_json(logs));
      }

      // One summary; a glTF's charts are summed (faces, iterations, time, flips), E_c is
      // area-weighted, eta and N_c are the largest over charts.
      size_t faces = 0, vertices = 0, flips = 0;
      double seconds = 0, energy = 0, area = 0;
      int iterations = 0, most = 0, eta = 0;
      bool converged = true;
      size_t skipped = 0, filled = 0;
      for (const auto& c : charts) {
        faces += c.mesh.triangle_count(), vertices += c.mesh.vertex_count(), flips += c.result.flips;
        filled += c.filled_holes;
        if (!c.skipped.empty()) {
          ++skipped;
          continue;
        }
        seconds += c.result.seconds, iterations += c.result.iterations;
        most = std::max(most, c.result.iterations), eta = std::max(eta, c.result.eta);
        converged = converged && c.result.converged;
        double a3 = 0;
        const auto& m = c.mesh;
        for (size_t t = 0; t < m.triangle_count(); ++t) {
          const double* p0 = &m.positions[3 * size_t(m.triangles[3 * t])];
          const double* p1 = &m.positions[3 * size_t(m.triangles[3 * t + 1])];
          const double* p2 = &m.positions[3 * size_t(m.triangles[3 * t + 2])];
          double e1[3], e2[3];
          for (int k = 0; k < 3; ++k) e1[k] = p1[k] - p0[k], e2[k] = p2[k] - p0[k];
          a3 += 0.5 * std::sqrt(std::pow(e1[1] * e2[2] - e1[2] * e2[1], 2) + std::pow(e1[2] * e2[0] - e1[0] * e2[2], 2) +
                                std::pow(e1[0] * e2[1] - e1[1] * e2[0], 2));
        }
        energy += a3 * c.result.energy, area += a3;
      }
      nlohmann::ordered_json report;
      if (charts.size() == 1 && skipped == 0 && filled == 0) {
        report = flatten::summary_json(charts[0].result, o.method, faces, vertices);
      } else {
        report["method"] = a->method;
        report["faces"] = faces;
        report["vertices"] = vertices;
        report["N_c"] = most;
        report["eta"] = eta;
        report["t_c_s"] = seconds;
        report["E_c"] = area > 0 ? energy / area : 0.0;
        report["s_per_iter"] = iterations ? seconds / iterations : 0.0;
        report["flips"] = flips;
        report["peak_rss_mb"] = flatten::peak_rss_mb();
        report["converged"] = converged;
        report["charts"] = nlohmann::ordered_json::array();
        for (const auto& c : charts) {
          auto j = flatten::summary_json(c.result, o.method, c.mesh.triangle_count(), c.mesh.vertex_count());
          j["chart"] = c.label;
          if (c.filled_holes) j["filled_holes"] = c.filled_holes;
          if (!c.skipped.empty()) j["skipped"] = c.skipped;
          report["charts"].push_back(j);
        }
      }
      report["input"] = a->input;
      report["output"] = a->output;
      if (gltf_in) {
        report["uv_sets_written"] = uv_sets;
        report["charts_skipped"] = skipped;
        report["holes_filled"] = filled;
        report["overlaps_new"] = overlaps_new;
        report["input_validation"] = checked;
      }
      // What a person reads: triangles, charts, time, flips, what was skipped and the UV
      // set written. The solver's own figures (eta, E_c) are in --report and -v.
      std::string extra = mesh_note;
      if (skipped) extra += ", " + std::to_string(skipped) + (skipped == 1 ? " chart" : " charts") + " skipped (input UVs kept)";
      if (filled) extra += ", " + std::to_string(filled) + (filled == 1 ? " hole" : " holes") + " filled for the solve";
      std::string sets;
      for (const auto& s : uv_sets) sets += (sets.empty() ? "" : ", ") + s;
      if (!sets.empty()) sets = " (new UV set " + sets + ")";
      // The whole asset before (measured before anything replaces it) and after.
      uint64_t in_bytes = 0, out_bytes = 0;
      if (gltf_in) {
        in_bytes = io::asset_bytes(a->input, g.refs()).total(), out_bytes = io::staged_asset_bytes(writer, a->output).total();
      } else {
        in_bytes = io::read_file(a->input).size();
        for (const auto& [path, size] : writer.staged())
          if (path == a->output) out_bytes = size;
      }
      report["input_bytes"] = in_bytes;
      report["output_bytes"] = out_bytes;
      g.write_report(report, writer);
      writer.commit();
      std::printf("%s (%s): %zu triangles%s, %s: %d iterations, %.3f s, %zu flips%s -> %s (%s)%s\n", a->input.c_str(),
                  human_bytes(in_bytes).c_str(), faces,
                  charts.size() > 1 ? (" in " + std::to_string(charts.size()) + " charts").c_str() : "", a->method.c_str(),
                  charts.size() == 1 ? iterations : most, seconds, flips, extra.c_str(), a->output.c_str(),
                  human_bytes(out_bytes).c_str(), sets.c_str());
      if (g.verbose) std::fprintf(stderr, "flatten: eta %d, E_c %.6f\n", eta, report["E_c"].get<double>());
      return 0;
    };
  });
}

}  // namespace uvpress::cli
