#include "io/palette_quantize.h"

#include <libimagequant.h>

#include <algorithm>
#include <memory>
#include <stdexcept>
#include <string>

namespace uvpress::io {

namespace {

struct Free {
  void operator()(liq_attr* p) const { liq_attr_destroy(p); }
  void operator()(liq_image* p) const { liq_image_destroy(p); }
  void operator()(liq_result* p) const { liq_result_destroy(p); }
};

}  // namespace

PaletteImage quantize_palette(const uint8_t* rgba, uint32_t width, uint32_t height, float dithering,
                              const std::vector<std::array<uint8_t, 4>>& fixed, const std::vector<uint8_t>* importance) {
  if (fixed.size() > 256) throw std::invalid_argument("quantize_palette: more than 256 fixed colours");
  PaletteImage out;
  out.indices.resize(size_t(width) * height);
  if (fixed.size() == 1) {  // libimagequant's palettes have 2 entries or more
    out.palette = fixed;
    return out;
  }
  std::unique_ptr<liq_attr, Free> attr(liq_attr_create());
  if (!attr) throw std::runtime_error("libimagequant: out of memory");
  // Fixed colours are reserved in the palette; with no room for more, they are the palette.
  if (liq_set_max_colors(attr.get(), fixed.empty() ? 256 : int(fixed.size())) != LIQ_OK)
    throw std::runtime_error("libimagequant: cannot set the palette's size");
  // Speed 1 (the slowest, best palette): textures are few and a palette is chosen once.
  liq_set_speed(attr.get(), 1);
  // Gamma 0: libimagequant's default (sRGB-like), which is how colour textures are stored.
  std::unique_ptr<liq_image, Free> image(liq_image_create_rgba(attr.get(), rgba, int(width), int(height), 0));
  if (!image) throw std::runtime_error("libimagequant: cannot take a " + std::to_string(width) + "x" + std::to_string(height) + " image");
  if (importance && importance->size() == size_t(width) * height) {
    // libimagequant takes the buffer as non-const (LIQ_COPY_PIXELS copies it), and a weight
    // of 0 as none at all.
    std::vector<uint8_t> weights(*importance);
    for (uint8_t& w : weights) w = std::max<uint8_t>(w, 1);
    if (liq_image_set_importance_map(image.get(), weights.data(), weights.size(), LIQ_COPY_PIXELS) != LIQ_OK)
      throw std::runtime_error("libimagequant: cannot set the importance map");
  }
  for (const auto& c : fixed)
    if (liq_image_add_fixed_color(image.get(), liq_color{c[0], c[1], c[2], c[3]}) != LIQ_OK)
      throw std::runtime_error("libimagequant: cannot reserve a palette colour");
  liq_result* raw = nullptr;
  if (liq_image_quantize(image.get(), attr.get(), &raw) != LIQ_OK || !raw) throw std::runtime_error("libimagequant: quantization failed");
  std::unique_ptr<liq_result, Free> result(raw);
  liq_set_dithering_level(result.get(), dithering);
  if (liq_write_remapped_image(result.get(), image.get(), out.indices.data(), out.indices.size()) != LIQ_OK)
    throw std::runtime_error("libimagequant: remapping failed");
  const liq_palette* palette = liq_get_palette(result.get());
  for (unsigned i = 0; i < palette->count; ++i)
    out.palette.push_back({palette->entries[i].r, palette->entries[i].g, palette->entries[i].b, palette->entries[i].a});
  if (!fixed.empty()) {
    // Every entry fixed, libimagequant keeps them in order, but gives an entry of alpha 0
    // back as (0, 0, 0, 0): the input's own entries are written, whose colour a renderer
    // still filters into its neighbours.
    bool same = out.palette.size() == fixed.size();
    for (size_t i = 0; same && i < fixed.size(); ++i) same = out.palette[i] == fixed[i] || (out.palette[i][3] == 0 && fixed[i][3] == 0);
    if (!same) throw std::runtime_error("libimagequant: the fixed palette was not kept");
    out.palette = fixed;
  }
  return out;
}

}  // namespace uvpress::io
