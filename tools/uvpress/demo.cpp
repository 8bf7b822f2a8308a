// uvpress demo -o DIR: writes the embedded default asset and runs the main job on it.
// Today that is the load / check / inspect path; reparam and eval join as they land.
#include "cli.h"

#include "io/gltf_io.h"
#include "pipeline/demo_asset.h"
#include "pipeline/inspect.h"

#include <cstdio>
#include <filesystem>

namespace uvpress::cli {

void add_demo(CLI::App& app, Globals& g) {
  auto* cmd = app.add_subcommand("demo", "Write the embedded demo asset to DIR and run uvpress on it");
  auto dir = std::make_shared<std::string>("uvpress-demo");
  cmd->add_option("-o,--output", *dir, "Output folder (created if missing)")->capture_default_str();
  cmd->callback([&g, dir] {
    g.action = [&g, dir] {
      auto t0 = std::chrono::steady_clock::now();
      std::filesystem::create_directories(*dir);
      const std::string asset = (std::filesystem::path(*dir) / "demo.glb").string();
      io::save_gltf(pipeline::make_demo_asset(), asset);
      g.stage("generate", t0);
      // Read it back from disk, as a user's file would be.
      io::GltfFile file = io::load_gltf(asset);
      auto info = pipeline::inspect(file);
      g.stage("inspect", t0);
      auto engine = g.make_engine();
      std::fputs(pipeline::format_inspection(info).c_str(), stdout);
      std::printf("demo: wrote %s on %s (%s)\n", asset.c_str(), engine->device().name.c_str(),
                  engine->device().backend.c_str());
      info["device"] = engine->device().name;
      info["backend"] = engine->device().backend;
      g.write_report(info);
      return 0;
    };
  });
}

}  // namespace uvpress::cli
