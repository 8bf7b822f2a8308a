#include "io/ktx2.h"

#include "core/error.h"
#include "io/astc_codec.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>

namespace uvpress::io {

namespace {

constexpr uint8_t kIdentifier[12] = {0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A};
constexpr uint32_t kModelAstc = 162;  // KHR_DF_MODEL_ASTC
constexpr uint32_t kPrimariesBt709 = 1, kTransferLinear = 1, kTransferSrgb = 2;
constexpr size_t kHeaderBytes = 80;  // identifier, 9 uint32, index (4 uint32, 2 uint64)

void put32(std::vector<uint8_t>& b, uint32_t v) {
  for (int i = 0; i < 4; ++i) b.push_back(uint8_t(v >> (8 * i)));
}
void set32(std::vector<uint8_t>& b, size_t at, uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + size_t(i)] = uint8_t(v >> (8 * i));
}
void set64(std::vector<uint8_t>& b, size_t at, uint64_t v) {
  for (int i = 0; i < 8; ++i) b[at + size_t(i)] = uint8_t(v >> (8 * i));
}
uint32_t get32(const std::vector<uint8_t>& b, size_t at) {
  return uint32_t(b[at]) | uint32_t(b[at + 1]) << 8 | uint32_t(b[at + 2]) << 16 | uint32_t(b[at + 3]) << 24;
}
uint64_t get64(const std::vector<uint8_t>& b, size_t at) { return uint64_t(get32(b, at)) | uint64_t(get32(b, at + 4)) << 32; }
void pad_to(std::vector<uint8_t>& b, size_t alignment) {
  while (b.size() % alignment) b.push_back(0);
}

}  // namespace

std::vector<uint8_t> write_ktx2_astc(uint32_t width, uint32_t height, uint32_t bx, uint32_t by, bool srgb,
                                     const std::vector<std::vector<uint8_t>>& levels) {
  const uint32_t vk = astc_vk_format(bx, by, srgb);
  if (vk == 0) throw std::invalid_argument("ktx2: no ASTC format for that block");
  if (levels.empty() || width == 0 || height == 0) throw std::invalid_argument("ktx2: no levels");
  for (size_t l = 0; l < levels.size(); ++l) {
    const uint32_t w = std::max(1u, width >> l), h = std::max(1u, height >> l);
    if (levels[l].size() != astc_bytes(w, h, bx, by)) throw std::invalid_argument("ktx2: level size does not match");
    if (l > 0 && std::max(width >> l, height >> l) == 0) throw std::invalid_argument("ktx2: too many levels");
  }
  const uint32_t count = uint32_t(levels.size());
  std::vector<uint8_t> b(kIdentifier, kIdentifier + 12);
  for (uint32_t v : {vk, 1u /*typeSize*/, width, height, 0u /*depth*/, 0u /*layers*/, 1u /*faces*/, count, 0u /*none*/})
    put32(b, v);
  const size_t index_at = b.size();
  b.resize(kHeaderBytes, 0);
  const size_t levels_at = b.size();
  b.resize(levels_at + 24 * size_t(count), 0);

  // Data format descriptor: total size, then one basic block with one sample.
  const size_t dfd_at = b.size();
  put32(b, 44);
  put32(b, 0);                      // vendorId KHRONOS (17 bits), descriptorType BASICFORMAT (15 bits)
  put32(b, 2u | (40u << 16));       // versionNumber 2, descriptorBlockSize 24 + 16
  b.insert(b.end(), {uint8_t(kModelAstc), uint8_t(kPrimariesBt709), uint8_t(srgb ? kTransferSrgb : kTransferLinear), 0});
  b.insert(b.end(), {uint8_t(bx - 1), uint8_t(by - 1), 0, 0});  // texelBlockDimension0..3
  b.insert(b.end(), {16, 0, 0, 0, 0, 0, 0, 0});                  // bytesPlane0..7
  // Sample: bitOffset 0, bitLength 127 (128 bits), channelType KHR_DF_CHANNEL_ASTC_DATA (0),
  // samplePosition 0, sampleLower 0, sampleUpper 0xFFFFFFFF.
  b.insert(b.end(), {0, 0, 127, 0, 0, 0, 0, 0});
  put32(b, 0);
  put32(b, 0xFFFFFFFFu);
  const size_t dfd_len = b.size() - dfd_at;

  // Key/value data, sorted by key, each entry padded to 4 bytes.
  const size_t kvd_at = b.size();
  for (const auto& [k, v] : {std::pair<std::string, std::string>{"KTXorientation", "rd"}, {"KTXwriter", "uvpress"}}) {
    put32(b, uint32_t(k.size() + 1 + v.size() + 1));
    b.insert(b.end(), k.begin(), k.end());
    b.push_back(0);
    b.insert(b.end(), v.begin(), v.end());
    b.push_back(0);
    pad_to(b, 4);
  }
  const size_t kvd_len = b.size() - kvd_at;

  // Levels, smallest first, each at a multiple of lcm(16-byte blocks, 4) = 16.
  std::vector<uint64_t> offsets(count);
  for (uint32_t l = count; l-- > 0;) {
    pad_to(b, 16);
    offsets[l] = b.size();
    b.insert(b.end(), levels[l].begin(), levels[l].end());
  }
  set32(b, index_at + 0, uint32_t(dfd_at));
  set32(b, index_at + 4, uint32_t(dfd_len));
  set32(b, index_at + 8, uint32_t(kvd_at));
  set32(b, index_at + 12, uint32_t(kvd_len));
  set64(b, index_at + 16, 0);  // no supercompression global data
  set64(b, index_at + 24, 0);
  for (uint32_t l = 0; l < count; ++l) {
    set64(b, levels_at + 24 * l + 0, offsets[l]);
    set64(b, levels_at + 24 * l + 8, levels[l].size());
    set64(b, levels_at + 24 * l + 16, levels[l].size());
  }
  return b;
}

Ktx2Info read_ktx2(const std::vector<uint8_t>& b, const std::string& name) {
  auto fail = [&](const std::string& why) { throw InputError(name, "KTX2: " + why); };
  if (b.size() < kHeaderBytes || !std::equal(kIdentifier, kIdentifier + 12, b.begin())) fail("not a KTX 2.0 file");
  Ktx2Info k;
  k.vk_format = get32(b, 12), k.type_size = get32(b, 16), k.width = get32(b, 20), k.height = get32(b, 24);
  k.depth = get32(b, 28), k.layers = get32(b, 32), k.faces = get32(b, 36), k.levels = get32(b, 40);
  k.supercompression = get32(b, 44);
  const uint64_t dfd_at = get32(b, 48), dfd_len = get32(b, 52), kvd_at = get32(b, 56), kvd_len = get32(b, 60);
  const uint64_t sgd_at = get64(b, 64), sgd_len = get64(b, 72);
  const uint64_t size = b.size();
  auto inside = [&](uint64_t at, uint64_t len) { return at <= size && len <= size - at; };
  if (k.width == 0 || k.width > 16384 || k.height > 16384) fail("width or height out of range");
  if (k.levels > 32) fail("more than 32 levels");
  const uint32_t count = std::max(1u, k.levels);
  if (!inside(kHeaderBytes, 24ull * count)) fail("level index runs past the end of the file");
  if (!inside(dfd_at, dfd_len) || !inside(kvd_at, kvd_len) || !inside(sgd_at, sgd_len)) fail("an index entry lies outside the file");
  for (uint32_t l = 0; l < count; ++l) {
    const size_t at = kHeaderBytes + 24 * size_t(l);
    Ktx2Level level{get64(b, at), get64(b, at + 8), get64(b, at + 16)};
    if (!inside(level.offset, level.length)) fail("level " + std::to_string(l) + " lies outside the file");
    k.level_index.push_back(level);
  }
  // The basic descriptor block (the first one), if there is one.
  if (dfd_len >= 4 + 24 && get32(b, dfd_at) == dfd_len) {
    const size_t d = dfd_at + 4;
    k.color_model = b[d + 8], k.color_primaries = b[d + 9], k.transfer = b[d + 10];
    k.block_x = uint32_t(b[d + 12]) + 1, k.block_y = uint32_t(b[d + 13]) + 1;
  } else if (dfd_len != 0) {
    fail("malformed data format descriptor");
  }
  k.srgb = k.transfer == kTransferSrgb;
  for (uint64_t at = kvd_at; at + 4 <= kvd_at + kvd_len;) {
    const uint32_t len = get32(b, at);
    if (len > kvd_at + kvd_len - at - 4) fail("malformed key/value data");
    const char* p = reinterpret_cast<const char*>(&b[at + 4]);
    const size_t key_len = strnlen(p, len);
    std::string key(p, key_len), value;
    if (key_len + 1 < len) value.assign(p + key_len + 1, strnlen(p + key_len + 1, len - key_len - 1));
    k.key_values.emplace_back(key, value);
    at += 4 + (uint64_t(len) + 3) / 4 * 4;
  }
  return k;
}

}  // namespace uvpress::io
