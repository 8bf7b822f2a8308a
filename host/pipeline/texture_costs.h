// Texture costs for reports (issue 18): per image texels, encoded bytes and VRAM with a
// full mip chain (RGBA8 and BC7/ASTC 4x4, core/texture_cost.h), and their totals. One form
// for reparam, copy and batch.
#pragma once

#include "core/texture_cost.h"
#include "io/gltf_io.h"

#include <nlohmann/json.hpp>

namespace uvpress::pipeline {

// {"texels", "bytes", "vram_rgba8_mips", "vram_bc7_mips"}
nlohmann::ordered_json cost_json(const TextureCost& cost, uint64_t bytes);

// Every image of `file`: [{image, name, format, size, texels, bytes, vram_rgba8_mips,
// vram_bc7_mips}] (a KTX2 or WebP image, which uvpress carries but does not decode: bytes
// only), and `totals` over them. Returns {"textures": [...], "totals": {...}}.
nlohmann::ordered_json image_costs(const io::GltfFile& file);

}  // namespace uvpress::pipeline
