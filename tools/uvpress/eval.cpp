// uvpress eval REFERENCE [OTHER ...] [--flatten] [--paper-baseline] [--cost-grid ...]
//   [--resolution auto|N] [--filter trilinear|bilinear] [--shading auto|unlit|lit] [--cost-axis texels|bytes]
//   [--report FILE.json] [--html DIR]: perceptual quality against pixel
// cost (image texels, or encoded bytes) over 20 dodecahedron views (seed paper 001, section 5.1) for the
// reference's layout (resized as users do), each other glTF of the same mesh (and as
// written), and the isometric (flatten) layout; see host/eval/eval.h.
#include "cli.h"
#include "progress.h"

#include "core/error.h"
#include "eval/eval.h"
#include "io/gltf_io.h"

#include <cstdio>
#include <filesystem>
#include <unistd.h>

namespace uvpress::cli {

CLI::Validator cost_grid_value() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        double c = 0;
        if (!CLI::detail::lexical_cast(s, c) || !(c > 0 && c <= 4)) return "cost grid value " + s + " is not in (0, 4]";
        return "";
      },
      "in (0, 4]");
}

void add_view_options(CLI::App* cmd, uint32_t& resolution, eval::TextureFilter& filter, const std::string& prefix) {
  cmd->add_option_function<std::string>(
         prefix + "resolution",
         [&resolution, prefix](const std::string& v) {
           if (v == "auto") {
             resolution = 0;
             return;
           }
           uint32_t n = 0;
           if (!CLI::detail::lexical_cast(v, n) || n < 8 || n > eval::kMaxResolution)
             throw CLI::ValidationError(prefix + "resolution", "must be auto or 8.." + std::to_string(eval::kMaxResolution));
           resolution = n;
         },
         (prefix == "--score-" ? std::string("reparam's candidates and guard: ") : std::string()) +
             "View images, pixels a side, or auto: the smallest side >= 512 at which 95% of the visible surface "
             "shows at most one texel per pixel, capped at " + std::to_string(eval::EvalOptions{}.resolution_cap) +
             " (views rolled and cropped to the asset where the cap binds; default auto)")
      ->type_name("auto|N");
  cmd->add_option_function<std::string>(
         prefix + "filter",
         [&filter, prefix](const std::string& v) {
           const auto f = eval::parse_texture_filter(v);
           if (!f) throw CLI::ValidationError(prefix + "filter", "must be trilinear or bilinear");
           filter = *f;
         },
         (prefix == "--score-" ? std::string("reparam's candidates and guard: ") : std::string()) +
             "How views sample textures: trilinear (mip-mapped, as engines do; default) or bilinear (level 0 only)")
      ->type_name("trilinear|bilinear");
}

void add_shading_option(CLI::App* cmd, eval::Shading& shading, const std::string& prefix) {
  cmd->add_option_function<std::string>(
         prefix + "shading",
         [&shading, prefix](const std::string& v) {
           const auto s = eval::parse_shading(v);
           if (!s) throw CLI::ValidationError(prefix + "shading", "must be auto, unlit or lit");
           shading = *s;
         },
         (prefix == "--score-" ? std::string("reparam's candidates and guard: ") : std::string()) +
             "q from the base colour's luminance (unlit) or from views lit through the normal, occlusion, "
             "metallic-roughness and emissive maps (lit); auto: lit when a material has a normal map (default)")
      ->type_name("auto|unlit|lit");
}

void add_eval(CLI::App& app, Globals& g) {
  auto* cmd = app.add_subcommand("eval", "Quality (mean GMSD over 20 views) against pixel cost for several UV layouts");
  struct Args {
    std::string reference;
    std::vector<std::string> others;
    bool flatten = false;
    bool paper_baseline = false;
    std::vector<double> grid;
    eval::EvalOptions view;  // resolution and filter
    double contact = 0;
    std::string html;
    std::optional<io::AstcOptions> codec;
    std::optional<io::AstcQuality> codec_quality;
    eval::CostAxis cost_axis = eval::CostAxis::Texels;
  };
  auto a = std::make_shared<Args>();
  cmd->add_option("reference", a->reference, "The input asset (.gltf/.glb): its layout and full texture are the reference")
      ->required();
  cmd->add_option("others", a->others, "Other glTF files of the same mesh (reparam output, xatlas, Blender ...)");
  cmd->add_flag("--flatten", a->flatten, "Also evaluate the isometric layout (charts flattened, packed, re-baked)");
  cmd->add_flag("--paper-baseline", a->paper_baseline,
                "Also evaluate the input layout re-baked and area-filtered like the others (the paper's protocol, "
                "layout \"input-rebaked\")");
  cmd->add_option("--cost-grid", a->grid, "Relative costs c_r, each in (0, 4], comma-separated (default 0.1,0.2,...,1.0)")
      ->delimiter(',')
      ->check(cost_grid_value());
  add_view_options(cmd, a->view.resolution, a->view.filter, "--");
  add_shading_option(cmd, a->view.shading, "--");
  cmd->add_option("--contact-cost", a->contact, "c_r of the contact sheet (default: the grid point nearest 0.25)");
  cmd->add_option("--html", a->html, "Write an offline HTML report into this folder");
  cmd->add_option_function<std::string>(
         "--codec",
         [a](const std::string& v) {
           if (v == "none") {
             a->codec.reset();
             return;
           }
           const auto b = v.rfind("astc-", 0) == 0 ? io::parse_astc_block(v.substr(5)) : std::nullopt;
           if (!b) throw CLI::ValidationError("--codec", "must be none or astc-WxH (4x4 5x4 5x5 6x5 6x6 8x5 8x6 8x8)");
           a->codec = io::AstcOptions{(*b)[0], (*b)[1], io::AstcQuality::Medium};
         },
         "Score the textures after this GPU codec (each mip level compressed and decoded by astcenc): q at equal "
         "compressed bytes (default none)")
      ->type_name("none|astc-WxH");
  cmd->add_option_function<std::string>(
         "--codec-quality",
         [a](const std::string& v) {
           a->codec_quality = io::parse_astc_quality(v);
           if (!a->codec_quality) throw CLI::ValidationError("--codec-quality", "must be fastest, fast, medium, thorough or exhaustive");
         },
         "astcenc's preset for --codec (default medium, as reparam --texture-format astc)")
      ->type_name("fastest|fast|medium|thorough|exhaustive");
  cmd->add_option_function<std::string>(
         "--cost-axis",
         [a](const std::string& v) {
           const auto axis = eval::parse_cost_axis(v);
           if (!axis) throw CLI::ValidationError("--cost-axis", "must be texels or bytes");
           a->cost_axis = *axis;
         },
         "What the savings compare at equal q: image texels, or bytes (each texture encoded as the input's image is, "
         "relative to that image's bytes; not with --codec) (default texels)")
      ->type_name("texels|bytes");
  cmd->callback([&g, a] {
    if (a->cost_axis == eval::CostAxis::Bytes && a->codec)
      throw CLI::ValidationError("--cost-axis", "bytes counts the input's own codec (PNG or JPEG); with --codec the cost "
                                                "is the codec's fixed-rate blocks, which go with texels");
    g.action = [&g, a] {
      auto t0 = std::chrono::steady_clock::now();
      g.prepare_outputs({}, {a->html});
      io::GltfFile ref = g.load_input(a->reference);
      std::vector<io::GltfFile> files;
      files.reserve(a->others.size());
      for (const auto& f : a->others) files.push_back(g.load_input(f));
      std::vector<eval::LayoutInput> others;
      for (size_t k = 0; k < files.size(); ++k) {
        std::string name = std::filesystem::path(a->others[k]).stem().string();
        for (const auto& o : others)
          if (o.name == name) name += "-" + std::to_string(k + 1);
        if (name == "input" || name == "flatten" || name == "input-rebaked") name += "-file";
        others.push_back({name, &files[k]});
      }
      g.stage("load", t0);
      auto engine = g.make_engine();
      eval::EvalOptions o;
      if (!a->grid.empty()) o.cost_grid = a->grid;
      o.resolution = a->view.resolution, o.filter = a->view.filter, o.shading = a->view.shading;
      o.flatten = a->flatten;
      o.paper_baseline = a->paper_baseline;
      o.contact_cost = a->contact;
      o.artifacts = !a->html.empty();
      o.codec = a->codec;
      if (o.codec && a->codec_quality) o.codec->quality = *a->codec_quality;
      o.cost_axis = a->cost_axis;
      eval::EvalArtifacts art;
      ProgressDisplay display(g.verbose);
      const eval::EvalResult r = eval::evaluate(ref, others, *engine, o, &art,
                                                [&](const std::string& stage, size_t done, size_t total) {
                                                  if (stage == "done") display.finish();  // eval's last call
                                                  else display(stage, done, total);
                                                });
      display.finish();
      g.stage("evaluate", t0);
      if (!a->html.empty()) eval::write_html_report(r, art, a->html);
      g.write_report(r.to_json());
      g.stage("write", t0);
      std::string summary;
      for (const auto& L : r.layouts)
        if (L.as_written) {
          char buf[160];
          std::snprintf(buf, sizeof buf, "; %s as written: c_r %.3f, q %.4g", L.name.c_str(), L.as_written->c_r,
                        L.as_written->q);
          summary += buf;
          if (L.as_written->bytes) {
            std::snprintf(buf, sizeof buf, " (%.3f of the input's bytes)", L.as_written->bytes_ratio);
            summary += buf;
          }
        }
      for (const auto& s : r.savings) {
        char buf[200];
        if (s.savings.points) {
          std::snprintf(buf, sizeof buf, "; %s vs %s: %.1f%% of the %s at equal q", s.layout.c_str(), s.vs.c_str(),
                        100 * s.savings.ratio, r.cost_axis == eval::CostAxis::Bytes ? "bytes" : "pixels");
          summary += buf;
        } else if (r.cost_axis == eval::CostAxis::Bytes && r.layout(s.vs)) {
          // Along bytes a curve keeps its cheapest points (LayoutResult::cost_q): say where
          // the one compared with is cheapest, so that "no saving" has its reason.
          const auto front = r.layout(s.vs)->cost_q(eval::CostAxis::Bytes);
          if (front.empty()) continue;
          std::snprintf(buf, sizeof buf, "; %s vs %s: no common q along bytes (%s's cheapest: q %.3g at %.3f of the bytes)",
                        s.layout.c_str(), s.vs.c_str(), s.vs.c_str(), front.front().second, front.front().first);
          summary += buf;
        }
      }
      if (!r.shading_warning.empty()) summary += "; " + r.shading_warning;
      const std::string codec = o.codec ? ", after ASTC " + io::block_name(*o.codec) + " " + io::to_string(o.codec->quality) : "";
      const std::string axis = r.cost_axis == eval::CostAxis::Bytes ? "image texels; savings in bytes, encoded as " + r.reference.encoding : "image texels";
      std::printf("eval: %zu layouts x %zu costs (%s; input resized %s%s), %zu views at %u px%s (%s, %.0f%% of "
                  "the surface resolved, %s), noise floor q %.2g, in %.1f s%s\n",
                  r.layouts.size(), o.cost_grid.size(), axis.c_str(), r.input_resize.c_str(), codec.c_str(), r.views,
                  r.resolution.resolution, r.resolution.cropped ? " cropped to the asset" : "", eval::to_string(r.filter),
                  100 * r.resolution.resolved_fraction,
                  r.lit ? "lit" : "unlit", r.noise_floor(), r.seconds.total, summary.c_str());
      return 0;
    };
  });
}

}  // namespace uvpress::cli
