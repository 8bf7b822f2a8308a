// uvpress demo -o DIR: writes the embedded default asset, re-parameterizes it at half the
// texels and evaluates input vs reparam vs the isometric layout over 20 views, with an
// HTML report: the whole product on an asset every machine has.
#include "cli.h"
#include "progress.h"

#include "eval/eval.h"
#include "io/gltf_io.h"
#include "pipeline/demo_asset.h"
#include "pipeline/inspect.h"
#include "pipeline/reparam.h"

#include <cstdio>
#include <filesystem>
#include <unistd.h>

namespace uvpress::cli {

void add_demo(CLI::App& app, Globals& g) {
  auto* cmd = app.add_subcommand("demo", "Write the embedded demo asset to DIR, reparam it and evaluate the result");
  auto dir = std::make_shared<std::string>("uvpress-demo");
  auto evaluations = std::make_shared<int>(40);
  cmd->add_option("-o,--output", *dir, "Output folder (created if missing)")->capture_default_str();
  cmd->add_option("--evaluations", *evaluations, "GP-BO evaluations per triangle")->capture_default_str()->check(CLI::Range(11, 1000));
  // eval's views, for the evaluation and for reparam's candidates and guard alike.
  auto view = std::make_shared<eval::EvalOptions>();
  add_view_options(cmd, view->resolution, view->filter, "--");
  cmd->callback([&g, dir, evaluations, view] {
    g.action = [&g, dir, evaluations, view] {
      namespace fs = std::filesystem;
      auto t0 = std::chrono::steady_clock::now();
      g.prepare_outputs({}, {*dir});
      const std::string input = (fs::path(*dir) / "demo.glb").string();
      const std::string output = (fs::path(*dir) / "demo-reparam.glb").string();
      io::save_gltf(pipeline::make_demo_asset(), input);
      g.stage("generate", t0);
      auto engine = g.make_engine();

      // reparam at half the texels.
      io::GltfFile original = io::load_gltf(input);
      io::GltfFile file = original;
      pipeline::ReparamOptions options;
      options.triangle.evaluations = *evaluations;
      options.score_resolution = view->resolution, options.score_filter = view->filter;
      eval::EvalOptions eo;
      eo.resolution = view->resolution, eo.filter = view->filter;
      eo.flatten = true;
      options.curve_costs = eo.cost_grid;  // reparam's own curve, as written, for the verdict
      ProgressDisplay display(g.verbose);
      auto progress = [&display](const std::string& stage, size_t done, size_t total) {
        if (stage == "done") display.finish();  // eval's last call
        else display(stage, done, total);
      };
      io::GltfFile reparamed;  // reparam's layout, even when the guard writes the resize
      const pipeline::ReparamResult report = pipeline::reparam(file, *engine, options, progress, &reparamed);
      io::save_gltf(file, output);
      g.stage("reparam", t0);

      // eval: input (its texture resized as users do) vs reparam's layout (vs the isometric
      // layout) over 20 views.
      eval::EvalArtifacts artifacts;
      const eval::EvalResult evaluation = eval::evaluate(original, {{"reparam", &reparamed}}, *engine, eo, &artifacts, progress);
      const std::string html = (fs::path(*dir) / "report").string();
      eval::write_html_report(evaluation, artifacts, html);
      g.stage("eval", t0);

      std::printf("demo: %s -> %s, cost ratio %.3f, %zu charts, %zu flipped triangles\n", input.c_str(), output.c_str(),
                  report.cost_ratio, report.charts, report.flips);
      for (const auto& s : evaluation.savings) {
        if (!s.savings.points) continue;  // the curves share no quality range
        std::printf("demo: %s looks as good as %s with %.2fx its pixels (eval: layouts re-baked from the input)\n",
                    s.layout.c_str(), s.vs.c_str(), s.savings.ratio);
      }
      // The verdict, measured on the spot: what was written and why.
      if (report.guard.ran) {
        const pipeline::Guard& gr = report.guard;
        char afar[96] = "";
        if (gr.far) std::snprintf(afar, sizeof afar, " (from afar, %u-px views: %.3g vs %.3g)", gr.far->resolution, gr.far->q_reparam, gr.far->q_resize);
        std::printf("demo: wrote %s: q %.3g for reparam's layout vs %.3g for a plain Lanczos resize to the same texels%s\n",
                    report.chosen == "reparam" ? "reparam's layout" : "the plain resize (it looks better)",
                    gr.q_reparam, gr.q_resize, afar);
      }
      // Pixels at equal q: reparam's own curve (at each c_r the best of its kept plan and the
      // best other, written and scored as written) against the input's resize curve, both at
      // eval's resolution.
      nlohmann::ordered_json verdict = nullptr;
      size_t verdict_ties = 0, verdict_points = 0;
      if (report.curve) {
        const double floor = evaluation.noise_floor();
        const auto sv = eval::pixel_ratio_at_equal_q(report.curve_cost_q(), evaluation.layouts[0].grid_q(), floor);
        verdict_ties = sv.ties, verdict_points = sv.points;
        if (sv.points && sv.ties == sv.points) {
          verdict = sv.ratio;
          std::printf("demo: reparam and a plain resize look the same at equal pixels (within eval's noise floor, q %.2g)\n", floor);
        } else if (sv.points) {
          verdict = sv.ratio;
          if (sv.ratio <= 1)
            std::printf("demo: reparam saves %.0f%% of the pixels of a plain resize at equal quality\n", 100 * (1 - sv.ratio));
          else
            std::printf("demo: reparam needs %.0f%% more pixels than a plain resize for equal quality\n", 100 * (sv.ratio - 1));
        } else {
          std::printf("demo: reparam's and the resize's curves share no quality range\n");
        }
      }
      std::printf("demo: report in %s/index.html (device: %s)\n", html.c_str(), engine->device().name.c_str());
      nlohmann::ordered_json out = {{"input", input}, {"output", output}, {"device", engine->device().name},
                                    {"backend", engine->device().backend}, {"reparam", report.to_json()}, {"eval", evaluation.to_json()},
                                    {"pixels_vs_resize_at_equal_q", verdict},
                                    {"pixels_vs_resize_levels", {{"points", verdict_points}, {"ties", verdict_ties}}}};
      g.write_report(out);
      return 0;
    };
  });
}

}  // namespace uvpress::cli
