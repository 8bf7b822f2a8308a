// uvpress info <asset>: triangles, UV sets and charts per primitive; size, colour space
// and users per image; whether anything tiles.
#include "cli.h"

#include "io/gltf_io.h"
#include "pipeline/inspect.h"

#include <cstdio>

namespace uvpress::cli {

void add_info(CLI::App& app, Globals& g) {
  auto* cmd = app.add_subcommand("info", "Describe a glTF asset: primitives, UV sets, charts, images and their users");
  auto input = std::make_shared<std::string>();
  cmd->add_option("input", *input, "glTF asset (.gltf or .glb)")->required();
  cmd->callback([&g, input] {
    g.action = [&g, input] {
      auto t0 = std::chrono::steady_clock::now();
      g.prepare_outputs({});  // --report
      io::GltfFile file = g.load_input(*input);
      g.stage("load", t0);
      auto info = pipeline::inspect(file);
      g.stage("inspect", t0);
      std::fputs(pipeline::format_inspection(info).c_str(), stdout);
      g.write_report(info);
      return 0;
    };
  });
}

}  // namespace uvpress::cli
