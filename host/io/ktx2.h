// The KTX 2.0 container (Khronos, KTX File Format Specification 2.0) for ASTC textures:
// writing one 2-D texture with its mip chain, and reading back what any writer put there.
//
// - write_ktx2_astc: one ASTC-compressed texture, no supercompression, every level given
//   (level 0 first, each max(1, W >> l) x max(1, H >> l) texels): header, level index,
//   data format descriptor (one basic block: colour model KHR_DF_MODEL_ASTC, BT.709
//   primaries, sRGB or linear transfer, the block footprint, 16 bytes a block, one
//   128-bit sample), key/value data (KTXorientation "rd", KTXwriter "uvpress"), then the
//   levels from the smallest to level 0, each at a 16-byte aligned offset, as the
//   specification orders them.
// - read_ktx2: the header, level index and basic data format descriptor of a KTX2 file,
//   every offset and length checked against the file (a corrupt or hostile file throws
//   InputError(name, reason) and is never read out of bounds), and the ASTC footprint
//   when vkFormat is an ASTC format. uvpress loads the KTX2 files it wrote beside a glTF
//   through it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace uvpress::io {

struct Ktx2Level {
  uint64_t offset = 0, length = 0, uncompressed_length = 0;
};

struct Ktx2Info {
  uint32_t vk_format = 0, type_size = 0, width = 0, height = 0, depth = 0, layers = 0, faces = 0, levels = 0;
  uint32_t supercompression = 0;
  uint32_t color_model = 0, color_primaries = 0, transfer = 0;  // from the basic DFD block
  uint32_t block_x = 1, block_y = 1;                            // texel block footprint
  bool srgb = false;                                            // transfer function is sRGB
  std::vector<Ktx2Level> level_index;                           // level 0 first
  std::vector<std::pair<std::string, std::string>> key_values;  // text values, NUL dropped
};

// Throws std::invalid_argument when levels do not fit (wrong count or sizes).
std::vector<uint8_t> write_ktx2_astc(uint32_t width, uint32_t height, uint32_t block_x, uint32_t block_y, bool srgb,
                                     const std::vector<std::vector<uint8_t>>& levels);

Ktx2Info read_ktx2(const std::vector<uint8_t>& bytes, const std::string& name);

}  // namespace uvpress::io
