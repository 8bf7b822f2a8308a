// GPU-ready textures beside a glTF (`--texture-format astc`): every image of the asset also
// written as an ASTC-compressed KTX2 file, for engines that upload KTX2 directly.
//
// - mip_levels: the full mip chain down to 1x1 that the KTX2 carries (engines cannot build
//   mips of a compressed texture): each level the exact box (area) filter of the level
//   above, as glGenerateMipmap builds it; colour channels of an sRGB texture in linear
//   light, alpha and data textures as stored.
// - encode_ktx2_astc: the image and its mip chain, each level compressed by astcenc
//   (io/astc_codec.h), in one KTX2 container (io/ktx2.h); sRGB formats for colour
//   textures, UNORM for data. decode_ktx2_level reads one level back (astcenc).
// - attach_astc_textures: every image of a loaded glTF encoded so, its colour space from
//   the materials that sample it (io/asset.h); the KTX2 bytes go into GltfFile::image_ktx2
//   and save_gltf writes them beside the output, each named in its image's
//   extras.uvpress_ktx2 (io/gltf_io.h). Returns per image what was written and the error of
//   level 0 as decoded (RMSE and PSNR over the stored 8-bit values of every channel).
#pragma once

#include "core/image.h"
#include "io/astc_codec.h"
#include "io/gltf_io.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace uvpress::io {

std::vector<Image> mip_levels(const Image& image, bool srgb);

std::vector<uint8_t> encode_ktx2_astc(const Image& image, bool srgb, const AstcOptions& options,
                                      Image* decoded_level0 = nullptr);

// Level `level` of a KTX2 file that holds ASTC blocks, decoded to `channels` channels.
// Throws InputError(name, reason) for a file that is not such a KTX2 or lacks the level.
Image decode_ktx2_level(const std::vector<uint8_t>& ktx2, uint32_t level, uint32_t channels, const std::string& name);

struct GpuTextureInfo {
  int image = -1;
  std::string name;
  bool srgb = true;
  uint32_t width = 0, height = 0, levels = 0, vk_format = 0;
  uint64_t bytes = 0;        // the KTX2 file
  double rmse = 0, psnr_db = 0;  // level 0 decoded against the image, 8-bit units
  double seconds = 0;
};

// Throws InputError(file.path, reason) when an image does not decode.
std::vector<GpuTextureInfo> attach_astc_textures(GltfFile& file, const AstcOptions& options);

// The reports' `gpu_textures`: [{image, name, format ("ktx2 astc 6x6 srgb"), vk_format,
// quality, size, levels, bytes, rmse_8bit, psnr_db, seconds}], one per attached copy.
nlohmann::ordered_json gpu_textures_report(const std::vector<GpuTextureInfo>& infos, const AstcOptions& options);

// Root-mean-square error of b against a (same size and channels) in 8-bit units, and the
// PSNR in dB it gives (99 for identical images).
double rmse_8bit(const Image& a, const Image& b);
double psnr_db(double rmse);

}  // namespace uvpress::io
