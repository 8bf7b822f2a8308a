// uvpress bench pack: how much of the image the packer puts under charts, and how fast. For
// the demo asset and the shared assets (and --asset FILE): each layout's own charts repacked
// (reparam --no-optimize, at each --costs value) and reparam's layout (its kept candidate at
// --cost), one JSON line per asset, layout and cost: packing efficiency (texels under
// charts / image texels), scale, atlas size, the texels the gutters keep empty, the chart
// texels kept relative to the input (eq. 21), and the packing's seconds (every atlas size
// and scale tried, the whole-texel re-pack of unreshaped charts included).
#include "bench.h"

#include "io/gltf_io.h"
#include "pipeline/demo_asset.h"
#include "pipeline/reparam.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>

namespace uvpress::cli {

void add_bench_pack(CLI::App& bench, Globals& g) {
  auto* cmd = bench.add_subcommand("pack", "Packing efficiency and seconds on the shared assets' own and reparam layouts");
  struct Args {
    std::vector<std::string> assets;
    std::string shared = "../shared/assets";
    std::vector<double> costs{1.0, 0.5};
    double reparam_cost = 0.5;
    bool no_reparam = false, only_given = false;
    pipeline::ReparamOptions reparam;
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("--asset", a->assets, "More glTF assets to measure (repeatable)");
  cmd->add_flag("--only", a->only_given, "Measure only the --asset files (not the demo and the shared assets)");
  cmd->add_option("--shared", a->shared, "Folder of the shared sample assets")->capture_default_str();
  cmd->add_option("--costs", a->costs, "Costs at which each asset's own charts are repacked")->delimiter(',')->capture_default_str();
  cmd->add_option("--cost", a->reparam_cost, "reparam --cost for the reparam layout")->capture_default_str()->check(CLI::Range(0.001, 1.0));
  cmd->add_flag("--no-reparam", a->no_reparam, "Only the own layouts (reparam's takes minutes per asset)");
  add_gutter_option(cmd, a->reparam.gutter);
  cmd->add_option("--block", a->reparam.block, "Chart alignment (4 for BCn)")->capture_default_str();
  add_keep_aspect_option(cmd, a->reparam.keep_aspect);
  cmd->add_flag("--pot", a->reparam.power_of_two, "Power-of-two sizes");
  cmd->callback([&g, a] {
    g.action = [&g, a] {
      const auto inputs = bench_assets(a->shared, a->only_given, a->assets);  // name, path ("" = the demo)
      auto engine = g.make_engine();
      for (const auto& [name, path] : inputs) {
        if (!path.empty() && !std::filesystem::exists(path)) {
          std::printf("%s\n", nlohmann::ordered_json{{"bench", "pack"}, {"asset", name}, {"skipped", "not found: " + path}}.dump().c_str());
          continue;
        }
        const io::GltfFile input = path.empty() ? pipeline::make_demo_asset() : io::load_gltf(path, g.refs());
        struct Run {
          std::string layout;
          double cost;
          bool optimize;
        };
        std::vector<Run> runs;
        for (double c : a->costs) runs.push_back({"own", c, false});
        if (!a->no_reparam) runs.push_back({"reparam", a->reparam_cost, true});
        for (const Run& run : runs) {
          pipeline::ReparamOptions ro = a->reparam;
          ro.cost = run.cost, ro.optimize = run.optimize, ro.guard = false;
          if (!run.optimize) ro.candidates = false, ro.least_squares_bake = false;
          io::GltfFile file = input;
          const pipeline::ReparamResult report = pipeline::reparam(file, *engine, ro);
          for (size_t index = 0; index < report.layouts.size(); ++index) {
            const pipeline::LayoutReport& l = report.layouts[index];
            if (l.untouched) continue;  // not packed
            const double image = double(l.atlas[0]) * double(l.atlas[1]);
            nlohmann::ordered_json line = {{"bench", "pack"},
                                           {"asset", name},
                                           {"layout", run.layout},
                                           {"uv_layout", int(index)},
                                           {"cost", run.cost},
                                           {"efficiency", l.packing_efficiency},
                                           {"scale", l.scale},
                                           {"atlas", l.atlas},
                                           {"gutter", l.gutter},
                                           {"gutter_share", l.gutter_texels / image},
                                           {"footprint_share", l.footprint_texels / image},
                                           {"free_share", std::max(0.0, 1.0 - (l.footprint_texels + l.gutter_texels) / image)},
                                           {"chart_cost_ratio", l.chart_cost_ratio},
                                           {"units", l.packing_units},
                                           {"seconds", l.pack_seconds}};
            if (run.optimize) line["candidate"] = report.layout;
            std::printf("%s\n", line.dump().c_str());
            std::fflush(stdout);
          }
        }
      }
      return 0;
    };
  });
}

}  // namespace uvpress::cli
