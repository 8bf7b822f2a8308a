// uvpress copy <in> -o <out>: load, check and write back a glTF, as .gltf or .glb. The
// round trip every other command builds on; also converts between the two forms.
#include "cli.h"

#include "core/error.h"
#include "io/asset.h"
#include "io/asset_bytes.h"
#include "io/gltf_io.h"
#include "pipeline/texture_costs.h"

#include <cstdio>
#include <filesystem>

namespace uvpress::cli {

void add_copy(CLI::App& app, Globals& g) {
  auto* cmd = app.add_subcommand("copy", "Read, check and rewrite a glTF asset (.gltf <-> .glb)");
  auto input = std::make_shared<std::string>(), output = std::make_shared<std::string>();
  cmd->add_option("input", *input, "glTF asset (.gltf or .glb)")->required();
  cmd->add_option("-o,--output", *output, "Output file (.gltf or .glb)")->required();
  auto gpu = std::make_shared<GpuOutputArgs>();
  add_gpu_output_options(cmd, *gpu);
  cmd->callback([&g, input, output, gpu] {
    g.action = [&g, input, output, gpu] {
      auto t0 = std::chrono::steady_clock::now();
      if (!io::is_gltf_output_path(*output))
        throw InputError(*output, "unsupported output format (use .gltf or .glb)");
      g.prepare_outputs({*output});
      nlohmann::ordered_json checked;
      io::GltfFile file = g.load_input(*input, &checked);
      io::build_asset(file);  // reject what later stages could not read
      g.stage("load", t0);
      std::string gpu_summary;
      const auto gpu_textures = attach_gpu_textures(file, *gpu, &gpu_summary);
      // The whole asset (JSON, buffers, images) before and after; images are carried byte
      // for byte, so their costs are the same on both sides. Measured before anything is
      // written (the output may replace the input).
      const uint64_t in = io::asset_bytes(*input, g.refs()).total();
      // The asset and its report appear together: a report that cannot be written leaves no asset.
      io::AtomicWriter writer;
      io::save_gltf(file, *output, {/*keep_image_names=*/true}, writer);
      const uint64_t out = io::staged_asset_bytes(writer, *output).total();
      const auto costs = pipeline::image_costs(file);
      nlohmann::ordered_json report = {{"input", *input}, {"output", *output}, {"input_bytes", in}, {"output_bytes", out},
                                       {"textures", costs["textures"]}, {"texture_totals", costs["totals"]},
                                       {"input_validation", checked}};
      if (!gpu_textures.is_null()) report["gpu_textures"] = gpu_textures;
      g.write_report(report, writer);
      writer.commit();
      g.stage("save", t0);
      std::printf("%s (%s) -> %s (%s), textures %s, VRAM (BC7, mips) %s%s\n", input->c_str(), human_bytes(in).c_str(),
                  output->c_str(), human_bytes(out).c_str(), human_bytes(costs["totals"]["bytes"].get<uint64_t>()).c_str(),
                  human_bytes(costs["totals"]["vram_bc7_mips"].get<uint64_t>()).c_str(), gpu_summary.c_str());
      return 0;
    };
  });
}

}  // namespace uvpress::cli
