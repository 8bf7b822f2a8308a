#include "pipeline/texture_costs.h"

#include "core/error.h"
#include "io/image_io.h"

namespace uvpress::pipeline {

using json = nlohmann::ordered_json;

json cost_json(const TextureCost& c, uint64_t bytes) {
  return {{"texels", c.texels}, {"bytes", bytes}, {"vram_rgba8_mips", c.vram_rgba8}, {"vram_bc7_mips", c.vram_bc7}};
}

json image_costs(const io::GltfFile& file) {
  json textures = json::array();
  TextureCost total;
  uint64_t bytes = 0;
  for (size_t i = 0; i < file.image_bytes.size(); ++i) {
    const auto& b = file.image_bytes[i];
    const std::string format = io::sniff_image_format(b.data(), b.size());
    json t = {{"image", i}, {"name", i < file.model.images.size() ? file.model.images[i].name : ""}, {"format", format}};
    bytes += b.size();
    if (format == "png" || format == "jpeg") {
      const io::ImageHeader h = io::read_image_header(b, file.path);
      const TextureCost c = texture_cost(h.width, h.height);
      t["size"] = {h.width, h.height};
      const json cost = cost_json(c, b.size());  // named: a temporary's items() would dangle
      for (auto& [key, value] : cost.items()) t[key] = value;
      total.texels += c.texels, total.vram_rgba8 += c.vram_rgba8, total.vram_bc7 += c.vram_bc7;
    } else {
      t["bytes"] = b.size();  // carried as it is; its texels are not read
    }
    textures.push_back(t);
  }
  return {{"textures", textures}, {"totals", cost_json(total, bytes)}};
}

}  // namespace uvpress::pipeline
