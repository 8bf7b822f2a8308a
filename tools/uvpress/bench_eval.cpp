// uvpress bench eval: seconds for a full q-c curve (the input layout, the default c_r grid,
// 20 views) on Duck (or --asset) on every backend, one JSON line per backend.
#include "bench.h"

#include "core/error.h"
#include "eval/eval.h"
#include "io/gltf_io.h"

#include <chrono>
#include <cstdio>
#include <filesystem>

namespace uvpress::cli {

void add_bench_eval(CLI::App& bench, Globals& g) {
  auto* cmd = bench.add_subcommand("eval", "Seconds for a full eval curve (20 views, default c_r grid) per backend");
  auto asset = std::make_shared<std::string>("../shared/assets/Duck/glTF-Binary/Duck.glb");
  auto view = std::make_shared<eval::EvalOptions>();
  cmd->add_option("--asset", *asset, "glTF asset")->capture_default_str();
  add_view_options(cmd, view->resolution, view->filter, "--");
  add_shading_option(cmd, view->shading, "--");
  cmd->callback([&g, asset, view] {
    g.action = [&g, asset, view] {
      if (!std::filesystem::exists(*asset)) throw InputError(*asset, "file not found (give --asset PATH)");
      io::GltfFile file = io::load_gltf(*asset, g.refs());
      eval::EvalOptions o;
      o.resolution = view->resolution, o.filter = view->filter, o.shading = view->shading;
      o.artifacts = false;
      for (auto& b : available_backends(g, "eval")) {
        const auto t0 = std::chrono::steady_clock::now();
        const eval::EvalResult r = eval::evaluate(file, {}, *b.engine, o);
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const auto d = b.engine->device();
        nlohmann::ordered_json line = {{"bench", "eval"},
                                       {"backend", d.backend},
                                       {"device", d.name},
                                       {"device_type", d.type},
                                       {"threads", d.threads},
                                       {"asset", *asset},
                                       {"triangles", r.triangles},
                                       {"views", r.views},
                                       {"resolution", r.resolution.resolution},
                                       {"resolution_cropped", r.resolution.cropped},
                                       {"view_pixels", r.resolution.view_pixels},
                                       {"filter", eval::to_string(r.filter)},
                                       {"shading", r.lit ? "lit" : "unlit"},
                                       {"resolved_fraction", r.resolution.resolved_fraction},
                                       {"c_r_points", o.cost_grid.size()},
                                       {"seconds", s},
                                       {"render_s", r.seconds.render},
                                       {"gmsd_s", r.seconds.gmsd},
                                       {"textures_s", r.seconds.textures},
                                       {"shading_s", r.seconds.shading}};  // lit views on the host
        std::printf("%s\n", line.dump().c_str());
        std::fflush(stdout);
      }
      return 0;
    };
  });
}

}  // namespace uvpress::cli
