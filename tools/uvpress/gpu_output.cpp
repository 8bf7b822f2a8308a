// --texture-format astc, --astc-block WxH, --astc-quality Q for the commands that write a
// glTF (reparam, copy): every image also written as an ASTC KTX2 file beside the output
// (host/io/gpu_textures.h), reported per texture.
#include "cli.h"

#include "io/gpu_textures.h"

namespace uvpress::cli {

void add_gpu_output_options(CLI::App* cmd, GpuOutputArgs& a) {
  cmd->add_option("--texture-format", a.format,
                  "source: textures in the input's codecs only; astc: also an ASTC-compressed KTX2 file (full mip "
                  "chain) per texture beside the output, named in each image's extras.uvpress_ktx2")
      ->capture_default_str()
      ->check(CLI::IsMember({"source", "astc"}));
  cmd->add_option_function<std::string>(
         "--astc-block",
         [&a](const std::string& v) {
           const auto b = io::parse_astc_block(v);
           if (!b) throw CLI::ValidationError("--astc-block", "must be one of 4x4 5x4 5x5 6x5 6x6 8x5 8x6 8x8");
           a.astc.block_x = (*b)[0], a.astc.block_y = (*b)[1];
           a.block_given = true;
         },
         "ASTC block footprint with --texture-format astc (default 6x6); reparam aligns charts to square blocks "
         "unless --block-align says otherwise")
      ->type_name("WxH");
  cmd->add_option_function<std::string>(
         "--astc-quality",
         [&a](const std::string& v) {
           const auto q = io::parse_astc_quality(v);
           if (!q) throw CLI::ValidationError("--astc-quality", "must be fastest, fast, medium, thorough or exhaustive");
           a.astc.quality = *q;
         },
         "astcenc's quality preset with --texture-format astc (default medium)")
      ->type_name("fastest|fast|medium|thorough|exhaustive");
}

uint32_t block_alignment(const GpuOutputArgs& a, uint32_t block, bool block_align_given) {
  // ASTC blocks other than 4x4 need charts aligned to the block: square footprints set it.
  if (a.format == "astc" && !block_align_given && a.astc.block_x == a.astc.block_y) return a.astc.block_x;
  return block;
}

nlohmann::ordered_json attach_gpu_textures(io::GltfFile& file, const GpuOutputArgs& a, std::string* summary) {
  if (a.format != "astc") return nullptr;
  const auto infos = io::attach_astc_textures(file, a.astc);
  uint64_t total = 0;
  double worst = 99;
  for (const auto& t : infos) total += t.bytes, worst = std::min(worst, t.psnr_db);
  if (summary && !infos.empty()) {
    char text[160];
    std::snprintf(text, sizeof text, ", KTX2 (ASTC %s, %s) %s, PSNR >= %.1f dB", io::block_name(a.astc).c_str(),
                  io::to_string(a.astc.quality), human_bytes(total).c_str(), worst);
    *summary = text;
  }
  return io::gpu_textures_report(infos, a.astc);
}

}  // namespace uvpress::cli
