// The host-side view of a glTF asset that every stage works on: triangle primitives with
// their positions and UV sets, and for each image which materials, roles, primitives and
// texCoord sets sample it. Built from a loaded GltfFile, which it never modifies.
#pragma once

#include "core/image.h"
#include "io/gltf_io.h"

#include <array>
#include <string>
#include <vector>

namespace uvpress::io {

struct UvSet {
  std::vector<float> uv;  // u v per vertex, as authored (normalized integers decoded)
  std::array<float, 2> min{0, 0}, max{0, 0};
  int component_type = 0;  // TINYGLTF_COMPONENT_TYPE_*
  bool normalized = false;
};

struct Primitive {
  int mesh = -1, primitive = -1;  // glTF mesh index and primitive index within it
  std::string mesh_name;
  int material = -1;
  std::vector<float> positions;   // x y z per vertex
  std::vector<uint32_t> indices;  // 3 per triangle (strips and fans are expanded)
  std::vector<UvSet> uv_sets;     // TEXCOORD_n at index n

  size_t vertex_count() const { return positions.size() / 3; }
  size_t triangle_count() const { return indices.size() / 3; }
};

enum class TextureRole { BaseColor, MetallicRoughness, Normal, Occlusion, Emissive, Other };
const char* to_string(TextureRole role);
// Colour textures are sRGB-encoded; normal, metallic-roughness and occlusion are data.
ColorSpace color_space_of(TextureRole role);

// KHR_texture_transform: uv' = T(offset) R(rotation) S(scale) uv.
struct TextureTransform {
  bool present = false;
  std::array<float, 2> offset{0, 0}, scale{1, 1};
  float rotation = 0;
  std::array<float, 2> apply(float u, float v) const;
};

// One way an image is sampled: a material slot, through a texture and sampler, by one
// primitive's texCoord set.
struct ImageUse {
  int material = -1;
  TextureRole role = TextureRole::Other;
  std::string slot;  // e.g. "pbrMetallicRoughness.baseColorTexture"
  int texture = -1;
  int primitive = -1;  // index into Asset::primitives
  int tex_coord = 0;
  TextureTransform transform;
  int wrap_s = 10497, wrap_t = 10497;  // REPEAT unless the sampler says otherwise
  // UVs (after the transform) leave [0,1] on a repeating axis: the texture tiles, so its
  // layout cannot be re-packed.
  bool tiled = false;
};

struct AssetImage {
  int index = -1;
  std::string name;  // image name, else its URI's file name, else "image N"
  std::string mime;
  ColorSpace color_space = ColorSpace::Srgb;
  bool mixed_color_spaces = false;  // sampled as colour by one use and as data by another
  std::vector<ImageUse> uses;
};

struct Asset {
  std::vector<Primitive> primitives;
  std::vector<AssetImage> images;
  size_t skipped_primitives = 0;  // points and lines: no surface to texture
};

// Throws InputError(file.path, reason) for accessors or indices out of range, wrong
// types, non-finite positions, and references to missing objects.
Asset build_asset(const GltfFile& file);

}  // namespace uvpress::io
