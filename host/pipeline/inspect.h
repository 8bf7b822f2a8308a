// What `uvpress info` reports about an asset, as JSON (the --report format) so that the
// CLI, tests and batch reports read the same figures.
#pragma once

#include "io/gltf_io.h"

#include <nlohmann/json.hpp>

namespace uvpress::pipeline {

// Per primitive: triangles, vertices, UV sets with their ranges and chart counts; per
// image: size, channels, bits, format, colour space and every use; whether anything tiles.
// Decodes image headers only. Throws InputError for malformed content.
nlohmann::ordered_json inspect(const io::GltfFile& file);

// The human-readable form of inspect()'s JSON.
std::string format_inspection(const nlohmann::ordered_json& info);

}  // namespace uvpress::pipeline
