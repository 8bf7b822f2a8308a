// uvpress flatten IN -o OUT [--assign]: the command line of pipeline/flatten.h (what is
// flattened, how, and what --assign does): checks the arguments, reads the input, writes
// the output, --log and --report together (io::AtomicWriter) and prints the summary line.
#include "cli.h"
#include "progress.h"

#include "core/error.h"
#include "flatten/flatten.h"
#include "flatten/report.h"
#include "io/asset_bytes.h"
#include "io/atomic_file.h"
#include "io/gltf_io.h"
#include "io/mesh_io.h"
#include "pipeline/flatten.h"
#include "pipeline/texture_costs.h"

#include <chrono>
#include <cstdio>
#include <functional>

namespace uvpress::cli {

namespace {

// flatten --assign: the isometric layout through reparam's packing and re-bake, staged in
// `writer`. Returns the report; `summary` gets the line to print once it is committed.
nlohmann::ordered_json assign_gltf(const Globals& g, const std::string& input, const std::string& output, double cost,
                                   const flatten::Options& o, io::AtomicWriter& writer, std::string& summary) {
  const auto t0 = std::chrono::steady_clock::now();
  pipeline::FlattenFiles files;
  files.input = input, files.output = output;
  io::GltfFile file = g.load_input(input, &files.input_validation);
  const io::AssetBytes in_files = io::asset_bytes(input, g.refs());
  const nlohmann::ordered_json old_costs = pipeline::image_costs(file)["totals"];
  auto engine = g.make_engine();
  ProgressDisplay progress(g.verbose);
  const pipeline::AssignResult a = pipeline::flatten_assign(file, *engine, cost, o, std::ref(progress));
  progress.finish();
  const pipeline::ReparamResult& r = a.reparam;
  io::save_gltf(file, output, {/*keep_image_names=*/true}, writer);
  const io::AssetBytes out_files = io::staged_asset_bytes(writer, output);
  for (const auto& w : r.warnings) std::fprintf(stderr, "uvpress: %s: warning: %s\n", input.c_str(), w.c_str());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  files.input_bytes = in_files.total(), files.output_bytes = out_files.total();
  const nlohmann::ordered_json report = pipeline::to_json(a, files, seconds);
  const nlohmann::ordered_json new_costs = pipeline::image_costs(file)["totals"];
  char cost_text[96];
  std::snprintf(cost_text, sizeof cost_text, "cost ratio %.3f%s", r.cost_ratio,
                a.at_density && r.cost_ratio < 0.98 * cost ? " (capped at the source texel density)" : "");
  std::string quality = "not scored on screen";
  if (r.q) {
    char text[96];
    std::snprintf(text, sizeof text, "on screen q %.3g against the input", *r.q);
    quality = text;
  }
  char line[2048];
  std::snprintf(line, sizeof line, "%s (%s, %llu texels) -> %s (%s, %llu texels): %zu charts flattened%s%s, textures re-baked into %s, %s, "
              "%s, %.1f s",
              input.c_str(), human_bytes(in_files.total()).c_str(), (unsigned long long)old_costs["texels"].get<uint64_t>(),
              output.c_str(), human_bytes(out_files.total()).c_str(), (unsigned long long)new_costs["texels"].get<uint64_t>(),
              a.flattened, a.kept ? (", " + std::to_string(a.kept) + " kept their UVs").c_str() : "",
              a.holes ? (", " + std::to_string(a.holes) + " holes filled for the solve").c_str() : "", a.uv_sets.c_str(),
              cost_text, quality.c_str(), seconds);
  summary = line;
  return report;
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
      pipeline::FlattenFiles files;
      files.input = a->input, files.output = a->output;
      pipeline::FlattenResult result;
      std::string mesh_note;  // OBJ/OFF: what the rewrite changed besides the UVs
      const auto stage = [&](const char* name) { g.stage(name, t0); };
      if (gltf_in) {
        io::GltfFile file = g.load_input(a->input, &files.input_validation);
        result = pipeline::flatten_gltf(file, o, stage, [&](const std::string& line) {
          std::fprintf(stderr, "uvpress: %s: warning: %s\n", a->input.c_str(), line.c_str());
        });
        const size_t flips = pipeline::totals(result).flips;
        if (flips) throw InputError(a->output, std::to_string(flips) + " flipped triangles in the UVs; nothing written");
        if (result.overlaps_new)
          throw InputError(a->output, std::to_string(result.overlaps_new) +
                                          " pairs of triangles overlap in the new UVs; nothing written");
        io::save_gltf(file, a->output, {/*keep_image_names=*/true}, writer);
      } else {
        // An OBJ keeps its materials (mtllib, usemtl) and normals (vn); the note says what
        // the rewrite changed besides: the input's own UVs replaced, group lines not kept.
        io::ObjExtras extras;
        const Mesh mesh = io::read_mesh(a->input, &extras);
        if (mesh.has_uvs()) mesh_note += ", the input's UVs (vt) replaced";
        if (extras.dropped) mesh_note += ", " + std::to_string(extras.dropped) + " o/g/s lines not kept";
        stage("load");
        Mesh written;
        result = pipeline::flatten_mesh(mesh, o, a->input, written, stage);
        const size_t flips = result.charts[0].result.flips;
        if (flips) throw InputError(a->output, std::to_string(flips) + " flipped triangles in the UVs; nothing written");
        io::write_obj(written, a->output, &extras, writer);
      }
      stage("save");

      if (!a->log.empty()) {
        std::vector<flatten::LabelledLog> logs;
        for (const auto& c : result.charts) logs.push_back({c.label, &c.result.log});
        writer.add(a->log, log_ext == ".csv" ? flatten::log_csv(logs) : flatten::log_json(logs));
      }

      // What a person reads: triangles, charts, time, flips, what was skipped and the UV
      // set written. The solver's own figures (eta, E_c) are in --report and -v.
      const pipeline::FlattenTotals t = pipeline::totals(result);
      std::string extra = mesh_note;
      if (t.skipped) extra += ", " + std::to_string(t.skipped) + (t.skipped == 1 ? " chart" : " charts") + " skipped (input UVs kept)";
      if (t.filled_holes)
        extra += ", " + std::to_string(t.filled_holes) + (t.filled_holes == 1 ? " hole" : " holes") + " filled for the solve";
      std::string sets;
      for (const auto& s : result.uv_sets) sets += (sets.empty() ? "" : ", ") + s;
      if (!sets.empty()) sets = " (new UV set " + sets + ")";
      // The whole asset before (measured before anything replaces it) and after.
      if (gltf_in) {
        files.input_bytes = io::asset_bytes(a->input, g.refs()).total();
        files.output_bytes = io::staged_asset_bytes(writer, a->output).total();
      } else {
        files.input_bytes = io::read_file(a->input).size();
        for (const auto& [path, size] : writer.staged())
          if (path == a->output) files.output_bytes = size;
      }
      const nlohmann::ordered_json report = pipeline::to_json(result, files);
      g.write_report(report, writer);
      writer.commit();
      std::printf("%s (%s): %zu triangles%s, %s: %d iterations, %.3f s, %zu flips%s -> %s (%s)%s\n", a->input.c_str(),
                  human_bytes(files.input_bytes).c_str(), t.faces,
                  result.charts.size() > 1 ? (" in " + std::to_string(result.charts.size()) + " charts").c_str() : "",
                  a->method.c_str(), result.charts.size() == 1 ? t.iterations : t.most_iterations, t.seconds, t.flips,
                  extra.c_str(), a->output.c_str(), human_bytes(files.output_bytes).c_str(), sets.c_str());
      if (g.verbose) std::fprintf(stderr, "flatten: eta %d, E_c %.6f\n", t.eta, report["E_c"].get<double>());
      return 0;
    };
  });
}

}  // namespace uvpress::cli
