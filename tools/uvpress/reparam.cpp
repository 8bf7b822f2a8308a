// uvpress reparam <in> -o <out>: new UVs under which a smaller texture looks as good on
// screen (perceptual loss, GMSD), every texture re-baked into them, a valid glTF written.
#include "cli.h"
#include "progress.h"

#include "core/error.h"
#include "io/asset_bytes.h"
#include "io/gltf_io.h"
#include "pipeline/reparam.h"
#include "pipeline/texture_costs.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <unistd.h>

namespace uvpress::cli {

void add_keep_aspect_option(CLI::App* cmd, bool& keep_aspect) {
  cmd->add_flag("--keep-aspect", keep_aspect,
                "New textures keep the source's aspect ratio (default: any shape from 1:2 to 2:1 of it, or to 1:4 "
                "and 4:1, where that packs the charts larger)");
}

void add_gutter_option(CLI::App* cmd, uint32_t& gutter) {
  cmd->add_option("--gutter", gutter,
                  "Texels between charts, half of it at image edges a sampler repeats across (default: mip-safe for "
                  "the new image's size: every mip level clean down to the first of side <= 64 texels, at most 16: 8 "
                  "texels at 362^2, 16 from 1024^2)")
      ->check(CLI::Range(0u, 64u));
}

CLI::Option* add_reparam_options(CLI::App* cmd, pipeline::ReparamOptions& o) {
  auto* cost = cmd->add_option("--cost", o.cost, "Texels of the new textures relative to the old (0.5: half)")
                   ->capture_default_str()
                   ->check(CLI::Range(0.001, 1.0));
  auto* size = cmd->add_option("--size", o.size, "New size of the driving texture's longer side, instead of --cost")
                   ->check(CLI::Range(8u, 16384u))
                   ->excludes(cost);
  cmd->add_option("--max-gmsd", o.max_gmsd, "Instead of --cost: the smallest textures whose 20-view GMSD is at most Q")
      ->check(CLI::Range(1e-5, 0.5))
      ->excludes(cost)
      ->excludes(size);
  cmd->add_flag("--pot", o.power_of_two, "Power-of-two texture sizes");
  add_view_options(cmd, o.score_resolution, o.score_filter, "--score-");
  add_shading_option(cmd, o.score_shading, "--score-");
  add_keep_aspect_option(cmd, o.keep_aspect);
  add_gutter_option(cmd, o.gutter);
  auto* block_align =
      cmd->add_option("--block-align", o.block,
                      "Align charts to N x N blocks (4 for BCn and ASTC 4x4; 5, 6, 8 for ASTC 5x5, 6x6, 8x8; default: 1, "
                      "or the --astc-block when square)")
          ->capture_default_str()
          ->check(CLI::IsMember({1u, 4u, 5u, 6u, 8u}));
  cmd->add_option("--epsilon", o.triangle.epsilon, "One GMSD bound for every triangle view (eq. 12; default: per triangle, from the loss a resize to the cost would cause)")
      ->check(CLI::Range(1e-4, 0.5))
      ->each([&o](const std::string&) { o.rate_control = false; });
  cmd->add_option("--evaluations", o.triangle.evaluations, "GP-BO evaluations per triangle")->capture_default_str()->check(CLI::Range(11, 1000));
  cmd->add_option("--view-size", o.triangle.view_size, "Per-triangle view size in pixels")->capture_default_str()->check(CLI::IsMember({16u, 32u, 48u, 64u}));
  cmd->add_option("--seed", o.triangle.seed, "Seed of the Bayesian optimization")->capture_default_str();
  cmd->add_option("--view-texels-per-pixel", o.triangle.min_texels_per_pixel,
                  "Small triangles' views magnify their texels no more than this (0: the paper's bounding-square view)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_flag("--early-stop,!--no-early-stop", o.triangle.early_stop,
                "Stop a triangle's search once it stalls (40+ evaluations, 30 without gain; the default); "
                "--no-early-stop spends all --evaluations");
  cmd->add_flag("--no-optimize", [&o](int64_t) { o.optimize = false; }, "Keep every triangle's shape: only repack and re-bake");
  cmd->add_flag("--resample-all", [&o](int64_t) { o.exact_texels = false; },
                "Resample every chart, also those that keep their shape (default: their texels are copied)");
  cmd->add_flag("--no-candidates", [&o](int64_t) { o.candidates = false; },
                "Build only the paper's layout (no floored-stretch or repacked candidates to choose from)");
  cmd->add_flag("--force-reparam", [&o](int64_t) { o.guard = false; },
                "Write reparam's layout even when a plain resize to the same texels looks better");
  return block_align;
}

void add_reparam(CLI::App& app, Globals& g) {
  auto* cmd = app.add_subcommand("reparam", "Re-parameterize an asset so that smaller textures look as good (GMSD)");
  auto input = std::make_shared<std::string>(), output = std::make_shared<std::string>();
  auto o = std::make_shared<pipeline::ReparamOptions>();
  cmd->add_option("input", *input, "glTF asset (.gltf or .glb)")->required();
  cmd->add_option("-o,--output", *output, "Output file (.gltf or .glb)")->required();
  auto* block_align = add_reparam_options(cmd, *o);
  auto gpu = std::make_shared<GpuOutputArgs>();
  add_gpu_output_options(cmd, *gpu);
  cmd->callback([&g, input, output, o, gpu, block_align] {
    o->block = block_alignment(*gpu, o->block, block_align->count() > 0);
    g.action = [&g, input, output, o, gpu] {
      auto t0 = std::chrono::steady_clock::now();
      if (!io::is_gltf_output_path(*output)) throw InputError(*output, "unsupported output format (use .gltf or .glb)");
      g.prepare_outputs({*output});  // before the work, not after it
      nlohmann::ordered_json checked;
      io::GltfFile file = g.load_input(*input, &checked);
      // The input as it is before anything is written (the output may replace it in place).
      const io::AssetBytes in_files = io::asset_bytes(*input, g.refs());
      const nlohmann::ordered_json old_costs = pipeline::image_costs(file)["totals"];
      auto engine = g.make_engine();
      const pipeline::ReparamOptions options = *o;
      ProgressDisplay progress(g.verbose);
      const pipeline::ReparamResult r = pipeline::reparam(file, *engine, options, std::ref(progress));
      progress.finish();
      nlohmann::ordered_json report = r.to_json();
      std::string gpu_summary;
      const auto gpu_textures = attach_gpu_textures(file, *gpu, &gpu_summary);
      if (!gpu_textures.is_null()) report["gpu_textures"] = gpu_textures;
      // The asset and its report are staged together and appear together: a report that
      // cannot be written leaves no asset (and an asset written in place is not replaced).
      io::AtomicWriter writer;
      io::save_gltf(file, *output, {/*keep_image_names=*/true}, writer);
      double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      // The whole asset before and after: JSON, buffers and images (or the .glb).
      const io::AssetBytes out_files = io::staged_asset_bytes(writer, *output);
      const uint64_t in_bytes = in_files.total(), out_bytes = out_files.total();
      for (const auto& w : r.warnings) std::fprintf(stderr, "uvpress: %s: warning: %s\n", input->c_str(), w.c_str());
      // Every image of the asset, re-baked or not.
      const nlohmann::ordered_json new_costs = pipeline::image_costs(file)["totals"];
      const uint64_t old_t = old_costs["texels"].get<uint64_t>(), new_t = new_costs["texels"].get<uint64_t>();
      // Triangles whose search never met eps keep their shape: say so on the summary line.
      std::string infeasible;
      if (const size_t n = r.triangles_infeasible)
        infeasible = ", " + std::to_string(n) + " of " + std::to_string(r.triangles_optimized) +
                     " triangles infeasible at epsilon (kept at the identity)";
      // A layout packed at the source texel density could not use the whole budget: say why
      // the ratio is below --cost.
      std::string capped;
      if (o->size == 0 && o->max_gmsd == 0 && r.capped_at_source_density() && r.cost_ratio < 0.98 * o->cost) {
        char text[96];
        std::snprintf(text, sizeof text, " (--cost %.3g: capped at the source texel density)", o->cost);
        capped = text;
      }
      // What was written, and how it compares on screen with the resize a user would do.
      std::string verdict;
      if (r.chosen == "untouched") {
        // Nothing was re-parameterized: say why instead of a cost ratio of 1 that reads as a result.
        std::string why;
        for (const auto& l : r.layouts)
          if (l.untouched) why += (why.empty() ? "" : "; ") + *l.untouched;
        verdict = "; nothing re-parameterized" + (why.empty() ? std::string(" (no textured layout)") : ": " + why);
      } else if (!r.guard.skipped.empty()) {
        verdict = "; not compared with a plain resize (eval cannot score this asset)";
      } else if (r.guard.ran) {
        // q up close (what the guard chooses by), then from afar where it was measured.
        const auto& far = r.guard.far;
        char text[320], afar[96] = "";
        if (far) std::snprintf(afar, sizeof afar, ", from afar %.3g vs %.3g", far->q_reparam, far->q_resize);
        if (r.chosen == "reparam")
          std::snprintf(text, sizeof text, "; on screen q %.3g vs %.3g%s for a plain resize to the same texels (%s layout kept%s)",
                        r.guard.q_reparam, r.guard.q_resize, afar, r.layout.c_str(),
                        r.guard.unseen.empty() ? "" : r.guard.unseen.size() == 1 ? "; 1 re-baked image unseen by q" : "; re-baked images unseen by q");
        else if (r.guard.q_resize == r.guard.q_reparam)
          std::snprintf(text, sizeof text, "; wrote a plain resize: it ties with reparam's layout on screen (q %.3g both)", r.guard.q_resize);
        else if (far)
          std::snprintf(text, sizeof text, "; wrote a plain resize: it looks better (q %.3g, from afar %.3g) than reparam's layout (q %.3g, %.3g)",
                        r.guard.q_resize, far->q_resize, r.guard.q_reparam, far->q_reparam);
        else
          std::snprintf(text, sizeof text, "; wrote a plain resize: it looks better (q %.3g) than reparam's layout (q %.3g)",
                        r.guard.q_resize, r.guard.q_reparam);
        verdict = text;
      }
      // Texture bytes as encoded, and VRAM block-compressed (BC7/ASTC 4x4) with mip-maps,
      // over every image of the asset (the report's texture_totals count the re-baked ones).
      const std::string textures = ", textures " + human_bytes(old_costs["bytes"].get<uint64_t>()) + " -> " +
                                   human_bytes(new_costs["bytes"].get<uint64_t>()) + ", VRAM (BC7, mips) " +
                                   human_bytes(old_costs["vram_bc7_mips"].get<uint64_t>()) + " -> " +
                                   human_bytes(new_costs["vram_bc7_mips"].get<uint64_t>());
      nlohmann::ordered_json out = {{"input", *input}, {"output", *output}, {"device", r.device.name},
                                    {"backend", r.device.backend}, {"seconds", seconds}, {"input_bytes", in_bytes},
                                    {"output_bytes", out_bytes},
                                    {"input_files", {{"file", in_files.file}, {"buffers", in_files.buffers}, {"images", in_files.images}, {"ktx2", in_files.ktx2}}},
                                    {"output_files", {{"file", out_files.file}, {"buffers", out_files.buffers}, {"images", out_files.images}, {"ktx2", out_files.ktx2}}}};
      out["input_validation"] = checked;
      for (auto& [key, value] : report.items())
        if (!out.contains(key)) out[key] = value;
      out["seconds"] = seconds;
      g.write_report(out, writer);
      writer.commit();
      std::printf("%s (%s, %llu texels) -> %s (%s, %llu texels)%s%s, cost ratio %.3f%s%s%s, %.1f s\n", input->c_str(),
                  human_bytes(in_bytes).c_str(), (unsigned long long)old_t, output->c_str(), human_bytes(out_bytes).c_str(),
                  (unsigned long long)new_t, textures.c_str(), gpu_summary.c_str(), r.cost_ratio, capped.c_str(),
                  infeasible.c_str(), verdict.c_str(), seconds);
      if (g.verbose)
        for (auto& [stage, s] : report["stages"].items()) std::fprintf(stderr, "%s: %.2f s\n", stage.c_str(), s.get<double>());  // every stage the report times
      return 0;
    };
  });
}

}  // namespace uvpress::cli
