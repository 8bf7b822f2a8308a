#include "io/gpu_textures.h"

#include "core/error.h"
#include "core/stopwatch.h"
#include "io/asset.h"
#include "io/image_io.h"
#include "io/ktx2.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace uvpress::io {

namespace {

float decode_srgb(float v) { return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f); }
float encode_srgb(float v) {
  v = std::clamp(v, 0.0f, 1.0f);
  return v <= 0.0031308f ? v * 12.92f : 1.055f * std::pow(v, 1 / 2.4f) - 0.055f;
}
bool is_colour(uint32_t c, uint32_t channels) { return channels <= 2 ? c == 0 : c < 3; }

// Exact box (area) filter of `src` to n texels along one axis: output texel i covers
// [i s, (i + 1) s) of the input, s = in / n, each input texel weighted by its overlap.
Image area_axis(const Image& src, uint32_t n, bool along_x) {
  const uint32_t in = along_x ? src.width : src.height, C = src.channels;
  Image out;
  out.width = along_x ? n : src.width, out.height = along_x ? src.height : n, out.channels = C, out.bits = src.bits;
  out.pixels.assign(size_t(out.width) * out.height * C, 0.0f);
  const double s = double(in) / n;
  for (uint32_t i = 0; i < n; ++i) {
    const double a = i * s, b = (i + 1) * s;
    for (uint32_t k = uint32_t(a); k < in && k < b; ++k) {
      const float w = float((std::min<double>(b, k + 1) - std::max<double>(a, k)) / s);
      if (w <= 0) continue;
      const uint32_t lines = along_x ? src.height : src.width;
      for (uint32_t j = 0; j < lines; ++j) {
        const size_t from = along_x ? (size_t(j) * src.width + k) * C : (size_t(k) * src.width + j) * C;
        const size_t to = along_x ? (size_t(j) * out.width + i) * C : (size_t(i) * out.width + j) * C;
        for (uint32_t c = 0; c < C; ++c) out.pixels[to + c] += w * src.pixels[from + c];
      }
    }
  }
  return out;
}

}  // namespace

std::vector<Image> mip_levels(const Image& image, bool srgb) {
  std::vector<Image> chain{image};
  const uint32_t C = image.channels;
  Image linear = image;
  if (srgb)
    for (size_t k = 0; k < linear.pixels.size(); ++k)
      if (is_colour(uint32_t(k % C), C)) linear.pixels[k] = decode_srgb(linear.pixels[k]);
  for (uint32_t l = 1; std::max(image.width >> (l - 1), image.height >> (l - 1)) > 1; ++l) {
    const uint32_t w = std::max(1u, image.width >> l), h = std::max(1u, image.height >> l);
    if (w != linear.width) linear = area_axis(linear, w, true);
    if (h != linear.height) linear = area_axis(linear, h, false);
    Image level = linear;
    if (srgb)
      for (size_t k = 0; k < level.pixels.size(); ++k)
        if (is_colour(uint32_t(k % C), C)) level.pixels[k] = encode_srgb(level.pixels[k]);
    chain.push_back(std::move(level));
  }
  return chain;
}

std::vector<uint8_t> encode_ktx2_astc(const Image& image, bool srgb, const AstcOptions& options, Image* decoded0) {
  AstcCodec codec(srgb, options);
  std::vector<std::vector<uint8_t>> levels;
  for (const Image& level : mip_levels(image, srgb)) levels.push_back(codec.compress(level));
  if (decoded0) *decoded0 = codec.decompress(levels[0].data(), levels[0].size(), image.width, image.height, image.channels);
  return write_ktx2_astc(image.width, image.height, options.block_x, options.block_y, srgb, levels);
}

Image decode_ktx2_level(const std::vector<uint8_t>& ktx2, uint32_t level, uint32_t channels, const std::string& name) {
  const Ktx2Info k = read_ktx2(ktx2, name);
  const bool astc = k.vk_format >= 157 && k.vk_format <= 172;
  if (!astc || k.supercompression != 0) throw InputError(name, "KTX2: not an uncompressed-container ASTC texture");
  if (astc_vk_format(k.block_x, k.block_y, k.srgb) != k.vk_format)
    throw InputError(name, "KTX2: vkFormat " + std::to_string(k.vk_format) + " does not match its data format descriptor");
  if (level >= k.level_index.size()) throw InputError(name, "KTX2: no level " + std::to_string(level));
  AstcOptions o;
  o.block_x = k.block_x, o.block_y = k.block_y;
  AstcCodec codec(k.srgb, o);
  const auto& L = k.level_index[level];
  const uint32_t w = std::max(1u, k.width >> level), h = std::max(1u, std::max(1u, k.height) >> level);  // height 0: 1-D
  try {
    return codec.decompress(ktx2.data() + L.offset, size_t(L.length), w, h, channels);
  } catch (const std::runtime_error& e) {
    throw InputError(name, std::string("KTX2: level ") + std::to_string(level) + ": " + e.what());
  }
}

double rmse_8bit(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels) throw std::invalid_argument("rmse: sizes differ");
  double sum = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    const double d = 255.0 * (double(a.pixels[i]) - b.pixels[i]);
    sum += d * d;
  }
  return a.pixels.empty() ? 0 : std::sqrt(sum / double(a.pixels.size()));
}

double psnr_db(double rmse) { return rmse <= 0 ? 99.0 : std::min(99.0, 20 * std::log10(255.0 / rmse)); }

std::vector<GpuTextureInfo> attach_astc_textures(GltfFile& file, const AstcOptions& options) {
  const Asset asset = build_asset(file);
  std::vector<GpuTextureInfo> out;
  file.image_ktx2.assign(file.image_bytes.size(), {});
  for (size_t i = 0; i < file.image_bytes.size(); ++i) {
    const Stopwatch t0;
    GpuTextureInfo info;
    info.image = int(i);
    info.name = i < asset.images.size() ? asset.images[i].name : "image " + std::to_string(i);
    info.srgb = i >= asset.images.size() || asset.images[i].color_space == ColorSpace::Srgb;
    Image image = decode_image(file.image_bytes[i], file.path);
    Image decoded;
    auto bytes = encode_ktx2_astc(image, info.srgb, options, &decoded);
    // The error of what a GPU samples: the stored 8-bit values, as the codec saw them.
    Image quantized = image;
    for (float& v : quantized.pixels) v = std::round(std::clamp(v, 0.0f, 1.0f) * 255.0f) / 255.0f;
    info.rmse = rmse_8bit(quantized, decoded);
    info.psnr_db = psnr_db(info.rmse);
    info.width = image.width, info.height = image.height;
    const Ktx2Info k = read_ktx2(bytes, file.path);
    info.levels = k.levels, info.vk_format = k.vk_format, info.bytes = bytes.size();
    file.image_ktx2[i].bytes = std::move(bytes);
    file.image_ktx2[i].source = image_fingerprint(file.image_bytes[i]);
    info.seconds = t0.seconds();
    out.push_back(std::move(info));
  }
  return out;
}

nlohmann::ordered_json gpu_textures_report(const std::vector<GpuTextureInfo>& infos, const AstcOptions& options) {
  nlohmann::ordered_json out = nlohmann::ordered_json::array();
  for (const GpuTextureInfo& t : infos)
    out.push_back({{"image", t.image},       {"name", t.name},
                   {"format", "ktx2 astc " + block_name(options) + (t.srgb ? " srgb" : " unorm")},
                   {"vk_format", t.vk_format}, {"quality", to_string(options.quality)},
                   {"size", {t.width, t.height}}, {"levels", t.levels},
                   {"bytes", t.bytes},       {"rmse_8bit", t.rmse},
                   {"psnr_db", t.psnr_db},   {"seconds", t.seconds}});
  return out;
}

}  // namespace uvpress::io
