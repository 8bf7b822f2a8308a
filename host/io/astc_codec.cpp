#include "io/astc_codec.h"

#include <astcenc.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace uvpress::io {

namespace {

struct Footprint {
  uint32_t x, y, vk_unorm;  // VK_FORMAT_ASTC_<x>x<y>_UNORM_BLOCK; SRGB is the next value
};
constexpr Footprint kFootprints[] = {{4, 4, 157}, {5, 4, 159}, {5, 5, 161}, {6, 5, 163},
                                     {6, 6, 165}, {8, 5, 167}, {8, 6, 169}, {8, 8, 171}};

const Footprint* find_footprint(uint32_t x, uint32_t y) {
  for (const auto& f : kFootprints)
    if (f.x == x && f.y == y) return &f;
  return nullptr;
}

float preset(AstcQuality q) {
  switch (q) {
    case AstcQuality::Fastest: return ASTCENC_PRE_FASTEST;
    case AstcQuality::Fast: return ASTCENC_PRE_FAST;
    case AstcQuality::Medium: return ASTCENC_PRE_MEDIUM;
    case AstcQuality::Thorough: return ASTCENC_PRE_THOROUGH;
    case AstcQuality::Exhaustive: return ASTCENC_PRE_EXHAUSTIVE;
  }
  return ASTCENC_PRE_MEDIUM;
}

void check(astcenc_error e, const char* what) {
  if (e != ASTCENC_SUCCESS) throw std::runtime_error(std::string("astcenc: ") + what + ": " + astcenc_get_error_string(e));
}

uint8_t to_u8(float v) { return uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); }

}  // namespace

const char* to_string(AstcQuality q) {
  switch (q) {
    case AstcQuality::Fastest: return "fastest";
    case AstcQuality::Fast: return "fast";
    case AstcQuality::Medium: return "medium";
    case AstcQuality::Thorough: return "thorough";
    case AstcQuality::Exhaustive: return "exhaustive";
  }
  return "medium";
}

std::optional<AstcQuality> parse_astc_quality(std::string_view t) {
  for (AstcQuality q : {AstcQuality::Fastest, AstcQuality::Fast, AstcQuality::Medium, AstcQuality::Thorough,
                        AstcQuality::Exhaustive})
    if (t == to_string(q)) return q;
  return std::nullopt;
}

std::string block_name(const AstcOptions& o) { return std::to_string(o.block_x) + "x" + std::to_string(o.block_y); }

std::optional<std::array<uint32_t, 2>> parse_astc_block(std::string_view t) {
  for (const auto& f : kFootprints)
    if (t == std::to_string(f.x) + "x" + std::to_string(f.y)) return std::array<uint32_t, 2>{f.x, f.y};
  return std::nullopt;
}

uint32_t astc_vk_format(uint32_t x, uint32_t y, bool srgb) {
  const Footprint* f = find_footprint(x, y);
  return f ? f->vk_unorm + (srgb ? 1 : 0) : 0;
}

uint64_t astc_bytes(uint32_t w, uint32_t h, uint32_t bx, uint32_t by) {
  return uint64_t((w + bx - 1) / bx) * ((h + by - 1) / by) * 16;
}

namespace {

// Runs `work(t)` for t in [0, threads) on as many OpenMP threads (astcenc splits the blocks
// among the thread indices of one context; small images take one: the others would find no
// work). Returns the last error any of them reported, or success.
template <class Work>
astcenc_error on_threads(unsigned threads, const Work& work) {
  astcenc_error error = ASTCENC_SUCCESS;
#pragma omp parallel for num_threads(threads) schedule(static, 1)
  for (int t = 0; t < int(threads); ++t) {
    const astcenc_error e = work(unsigned(t));
    if (e != ASTCENC_SUCCESS) {
#pragma omp critical
      error = e;
    }
  }
  return error;
}

}  // namespace

AstcCodec::AstcCodec(bool srgb, const AstcOptions& o) : options_(o) {
  if (!find_footprint(o.block_x, o.block_y))
    throw std::invalid_argument("ASTC block " + block_name(o) + " is not one of 4x4 5x4 5x5 6x5 6x6 8x5 8x6 8x8");
  astcenc_config config;
  check(astcenc_config_init(srgb ? ASTCENC_PRF_LDR_SRGB : ASTCENC_PRF_LDR, o.block_x, o.block_y, 1, preset(o.quality), 0,
                            &config),
        "config");
#ifdef _OPENMP
  threads_ = unsigned(std::max(1, omp_get_max_threads()));
#else
  threads_ = 1;  // built without OpenMP (the fuzz targets): one thread, the same blocks
#endif
  check(astcenc_context_alloc(&config, threads_, &context_), "context");
}

AstcCodec::~AstcCodec() {
  if (context_) astcenc_context_free(context_);
}

std::vector<uint8_t> AstcCodec::compress(const Image& image) {
  const uint32_t C = image.channels;
  if (C < 1 || C > 4 || image.width == 0 || image.height == 0) throw std::invalid_argument("astc: empty image");
  const size_t n = size_t(image.width) * image.height;
  std::vector<uint8_t> rgba(n * 4);
  for (size_t i = 0; i < n; ++i) {
    const float* p = &image.pixels[i * C];
    const bool grey = C < 3;
    rgba[i * 4 + 0] = to_u8(p[0]);
    rgba[i * 4 + 1] = to_u8(grey ? p[0] : p[1]);
    rgba[i * 4 + 2] = to_u8(grey ? p[0] : p[2]);
    rgba[i * 4 + 3] = C == 2 ? to_u8(p[1]) : C == 4 ? to_u8(p[3]) : 255;
  }
  void* slices[1] = {rgba.data()};
  astcenc_image img{image.width, image.height, 1, ASTCENC_TYPE_U8, slices};
  const astcenc_swizzle swz{ASTCENC_SWZ_R, ASTCENC_SWZ_G, ASTCENC_SWZ_B, ASTCENC_SWZ_A};
  std::vector<uint8_t> out(astc_bytes(image.width, image.height, options_.block_x, options_.block_y));
  const astcenc_error error = on_threads(n < 64 * 64 ? 1 : threads_, [&](unsigned t) {
    return astcenc_compress_image(context_, &img, &swz, out.data(), out.size(), t);
  });
  astcenc_compress_reset(context_);
  check(error, "compress");
  return out;
}

Image AstcCodec::decompress(const uint8_t* data, size_t size, uint32_t w, uint32_t h, uint32_t channels) {
  if (size != astc_bytes(w, h, options_.block_x, options_.block_y))
    throw std::runtime_error("astc: " + std::to_string(size) + " bytes are not one " + std::to_string(w) + "x" +
                             std::to_string(h) + " level of " + block_name(options_) + " blocks");
  const size_t n = size_t(w) * h;
  std::vector<uint8_t> rgba(n * 4);
  void* slices[1] = {rgba.data()};
  astcenc_image img{w, h, 1, ASTCENC_TYPE_U8, slices};
  const astcenc_swizzle swz{ASTCENC_SWZ_R, ASTCENC_SWZ_G, ASTCENC_SWZ_B, ASTCENC_SWZ_A};
  const astcenc_error error = on_threads(n < 64 * 64 ? 1 : threads_, [&](unsigned t) {
    return astcenc_decompress_image(context_, data, size, &img, &swz, t);
  });
  astcenc_decompress_reset(context_);
  check(error, "decompress");
  Image out;
  out.width = w, out.height = h, out.channels = std::clamp(channels, 1u, 4u), out.bits = 8;
  out.pixels.resize(n * out.channels);
  const uint32_t C = out.channels;
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* p = &rgba[i * 4];
    float* q = &out.pixels[i * C];
    if (C < 3) {
      q[0] = p[0] / 255.0f;
      if (C == 2) q[1] = p[3] / 255.0f;
    } else {
      for (uint32_t c = 0; c < C; ++c) q[c] = p[c] / 255.0f;
    }
  }
  return out;
}

Image astc_round_trip(const Image& image, bool srgb, const AstcOptions& options) {
  AstcCodec codec(srgb, options);
  const auto blocks = codec.compress(image);
  return codec.decompress(blocks.data(), blocks.size(), image.width, image.height, image.channels);
}

}  // namespace uvpress::io
