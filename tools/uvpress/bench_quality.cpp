// uvpress bench quality: does reparam beat the resize a user would do? For the demo asset
// and the shared assets (and --asset FILE): reparam at --cost, then eval of its kept layout
// against the input (the input curve is the Lanczos-3 resize) and the isometric layout.
// One JSON line per asset: the pixel ratios at equal q from reparam's own curve (whatever
// the guard wrote; at each cost the best of the layouts reparam chose among, built into
// that budget: ReparamOptions::curve_costs), q at the output cost for the written file and for the
// resize, what the guard chose, and seconds. q is the lit q for assets with normal maps
// (eval's --shading auto, the default of --shading and --score-shading): the line says
// which (`shading`: eval's, `score_shading`: reparam's guard and curve).
#include "bench.h"

#include "core/error.h"
#include "eval/eval.h"
#include "io/gltf_io.h"
#include "pipeline/demo_asset.h"
#include "pipeline/reparam.h"

#include <chrono>
#include <cstdio>
#include <filesystem>

namespace uvpress::cli {

namespace {

nlohmann::ordered_json ratio_vs(const eval::EvalResult& ev, const std::string& vs, std::string* why) {
  for (const auto& s : ev.savings)
    if (s.layout == "reparam" && s.vs == vs) {
      if (!s.savings.points) {
        *why += "reparam's and " + vs + "'s curves share no q range; ";
        return nullptr;
      }
      return s.savings.ratio;
    }
  *why += "no " + vs + " curve; ";
  return nullptr;
}

}  // namespace

void add_bench_quality(CLI::App& bench, Globals& g) {
  auto* cmd = bench.add_subcommand("quality", "reparam against a plain resize on real assets (pixel ratio at equal q)");
  struct Args {
    std::vector<std::string> assets;
    std::string shared = "../shared/assets";
    pipeline::ReparamOptions reparam;
    eval::EvalOptions view;  // eval's resolution and filter
    bool only_given = false;
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("--asset", a->assets, "More glTF assets to measure (repeatable)");
  cmd->add_flag("--only", a->only_given, "Measure only the --asset files (not the demo and the shared assets)");
  cmd->add_option("--shared", a->shared, "Folder of the shared sample assets")->capture_default_str();
  cmd->add_option("--cost", a->reparam.cost, "reparam --cost")->capture_default_str()->check(CLI::Range(0.001, 1.0));
  cmd->add_option("--evaluations", a->reparam.triangle.evaluations, "reparam --evaluations")->capture_default_str()->check(CLI::Range(11, 1000));
  cmd->add_flag("--early-stop,!--no-early-stop", a->reparam.triangle.early_stop, "reparam --early-stop (the default) or --no-early-stop");
  cmd->add_option("--seed", a->reparam.triangle.seed, "reparam --seed")->capture_default_str();
  add_view_options(cmd, a->view.resolution, a->view.filter, "--");
  add_shading_option(cmd, a->view.shading, "--");
  add_view_options(cmd, a->reparam.score_resolution, a->reparam.score_filter, "--score-");
  add_shading_option(cmd, a->reparam.score_shading, "--score-");
  cmd->callback([&g, a] {
    g.action = [&g, a] {
      const auto inputs = bench_assets(a->shared, a->only_given, a->assets);  // name, path ("" = the demo)
      auto engine = g.make_engine();
      const auto d = engine->device();
      for (const auto& [name, path] : inputs) {
        nlohmann::ordered_json line = {{"bench", "quality"}, {"asset", name}, {"backend", d.backend}, {"device", d.name}};
        if (!path.empty() && !std::filesystem::exists(path)) {
          line["skipped"] = "not found: " + path;
          std::printf("%s\n", line.dump().c_str());
          continue;
        }
        const auto t0 = std::chrono::steady_clock::now();
        const io::GltfFile input = path.empty() ? pipeline::make_demo_asset() : io::load_gltf(path, g.refs());
        io::GltfFile written = input, layout;
        pipeline::ReparamOptions ro = a->reparam;
        ro.curve_costs = eval::EvalOptions{}.cost_grid;  // reparam's own curve, as written
        const pipeline::ReparamResult r = pipeline::reparam(written, *engine, ro, {}, &layout);
        const nlohmann::ordered_json report = r.to_json();
        line["chosen"] = r.chosen;
        line["layout"] = r.layout;
        line["cost_ratio"] = r.cost_ratio;
        line["q_reparam"] = r.guard.ran ? nlohmann::ordered_json(r.guard.q_reparam) : nlohmann::ordered_json(nullptr);
        line["q_resize"] = r.guard.ran ? nlohmann::ordered_json(r.guard.q_resize) : nlohmann::ordered_json(nullptr);
        // What the written textures cost in bytes beside what they look like: new / old, and
        // new / the input resized to the same texels and encoded alike (issue 18's two ratios).
        const auto& tt = r.texture_totals;
        if (tt.old_bytes > 0 && tt.resize_bytes > 0)
          line["texture_bytes"] = {{"old", tt.old_bytes}, {"new", tt.new_bytes}, {"resize", tt.resize_bytes},
                                   {"ratio", double(tt.new_bytes) / double(tt.old_bytes)},
                                   {"vs_resize", double(tt.new_bytes) / double(tt.resize_bytes)}};
        // The guard's views from afar (coarse mip levels): reparam's file and the resize.
        if (r.guard.far)
          line["far"] = {{"resolution", r.guard.far->resolution}, {"q_reparam", r.guard.far->q_reparam}, {"q_resize", r.guard.far->q_resize},
                         {"noise_floor", r.guard.far->noise_floor}};
        // reparam's guard and curve scored with this shading (its --score-shading).
        line["score_shading"] = r.scoring ? eval::to_string(r.scoring->shading) : "";
        const std::vector<std::pair<double, double>> curve = r.curve_cost_q();
        std::string why;
        if (r.chosen == "untouched") {
          line["ratio_vs_resize"] = nullptr, line["ratio_vs_isometric"] = nullptr;
          why = "reparam left every layout untouched";
        } else {
          eval::EvalOptions eo;
          eo.resolution = a->view.resolution, eo.filter = a->view.filter, eo.shading = a->view.shading;
          eo.flatten = true;
          eo.artifacts = false;
          const eval::EvalResult ev = eval::evaluate(input, {{"reparam", &layout}}, *engine, eo);
          // The ratios from reparam's own curve: at each cost the best of its kept plan and
          // the best other, built and scored as written (ReparamOptions::curve_costs),
          // against the input's resize curve and the isometric layout's curve. Beside them,
          // eval's protocol (the layout's full texture re-baked
          // from the input at c_r 1, then resized), which charges every layout a re-bake.
          line["ratio_vs_resize"] = nullptr, line["ratio_vs_isometric"] = nullptr;
          for (const auto& L : ev.layouts) {
            const std::string& name = L.name;
            if (name != "input" && name != "flatten") continue;
            // Levels where the two curves are within eval's noise floor count as ties (1).
            const double floor = ev.noise_floor();
            const auto s = eval::pixel_ratio_at_equal_q(curve, L.grid_q(), floor);
            const std::string key = name == "input" ? "ratio_vs_resize" : "ratio_vs_isometric";
            line[key + "_ties"] = s.ties, line["noise_floor"] = floor;
            if (s.points) line[key] = s.ratio;
            else line[key] = nullptr, why += "reparam's curve and " + name + "'s share no q range; ";
          }
          line["ratio_vs_resize_rebaked"] = ratio_vs(ev, "input", &why);
          line["ratio_vs_isometric_rebaked"] = ratio_vs(ev, "flatten", &why);
          line["curve"] = report.contains("curve") ? report["curve"] : nlohmann::ordered_json(nullptr);
          line["input_resize"] = ev.input_resize;
          // Which q the ratios and q values are (auto: lit for assets with normal maps), and
          // both shadings' noise floors when lit.
          line["shading"] = ev.lit ? "lit" : "unlit";
          if (!ev.shading_warning.empty()) line["shading_warning"] = ev.shading_warning;
        }
        if (!why.empty()) line["why_null"] = why;
        line["candidates"] = report["candidates"];
        line["triangles"] = r.triangles_optimized;
        line["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::printf("%s\n", line.dump().c_str());
        std::fflush(stdout);
      }
      return 0;
    };
  });
}

}  // namespace uvpress::cli
