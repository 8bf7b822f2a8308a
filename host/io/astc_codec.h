// ASTC block compression through Arm's astcenc (Debian's libastcenc-dev, 4.2), LDR only,
// the 2-D block footprints from 4x4 to 8x8 (4x4, 5x4, 5x5, 6x5, 6x6, 8x5, 8x6, 8x8).
//
// - AstcCodec: one astcenc context for a profile, footprint and quality preset, reused for
//   every image (and mip level) it is given; compress and decompress run on every OpenMP
//   thread (astcenc splits an image's blocks between the threads that call it). Colour
//   textures use the sRGB profile (what VK_FORMAT_ASTC_*_SRGB_BLOCK decodes), data textures
//   the linear one; texels go in and come out as the stored 8-bit values. Grey is
//   replicated into R, G and B, a missing alpha is opaque; decompress returns the channel
//   count asked for. Blocks are 16 bytes in row-major block order, partial blocks at the
//   right and bottom edges padded by the codec.
// - astc_round_trip: an image compressed and decoded again, as a GPU would sample it (eval's
//   --codec measures q on this).
// - astc_vk_format, astc_bytes, parse_astc_block, parse_astc_quality: the Vulkan format a
//   KTX2 file names, the payload size of one level, and the CLI's spellings ("6x6";
//   "fastest", "fast", "medium", "thorough", "exhaustive": astcenc's presets).
#pragma once

#include "core/image.h"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

struct astcenc_context;

namespace uvpress::io {

enum class AstcQuality { Fastest, Fast, Medium, Thorough, Exhaustive };
const char* to_string(AstcQuality quality);
std::optional<AstcQuality> parse_astc_quality(std::string_view text);

struct AstcOptions {
  uint32_t block_x = 6, block_y = 6;
  AstcQuality quality = AstcQuality::Medium;
};
std::string block_name(const AstcOptions& options);  // "6x6"
// "WxH" for one of the footprints above; nullopt otherwise.
std::optional<std::array<uint32_t, 2>> parse_astc_block(std::string_view text);

// VK_FORMAT_ASTC_<W>x<H>_{UNORM,SRGB}_BLOCK, 0 for a footprint not listed above.
uint32_t astc_vk_format(uint32_t block_x, uint32_t block_y, bool srgb);
// Bytes of one width x height level: 16 per block, partial blocks counted whole.
uint64_t astc_bytes(uint32_t width, uint32_t height, uint32_t block_x, uint32_t block_y);

class AstcCodec {
 public:
  // Throws std::invalid_argument for a footprint not listed above, std::runtime_error when
  // astcenc refuses the configuration.
  AstcCodec(bool srgb, const AstcOptions& options);
  ~AstcCodec();
  AstcCodec(const AstcCodec&) = delete;
  AstcCodec& operator=(const AstcCodec&) = delete;

  std::vector<uint8_t> compress(const Image& image);
  // `channels` (1..4) of the result; throws std::runtime_error when `size` is not
  // astc_bytes(width, height, ...) or astcenc fails.
  Image decompress(const uint8_t* data, size_t size, uint32_t width, uint32_t height, uint32_t channels);

 private:
  astcenc_context* context_ = nullptr;
  unsigned threads_ = 1;
  AstcOptions options_;
};

Image astc_round_trip(const Image& image, bool srgb, const AstcOptions& options);

}  // namespace uvpress::io
