// Internal to host/eval: one layout as eval renders it (primitives sampling the driving
// texture, concatenated), texture re-baking and the isometric layout.
#pragma once

#include "atlas/rebake.h"
#include "core/image.h"
#include "io/gltf_io.h"
#include "lit.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace uvpress::eval::detail {

// One image a material of the layout samples, as lit shading needs it: `kind` says how it
// is filtered and re-baked (Color: sRGB; Data: occlusion / metallic-roughness as stored;
// Normal: tangent-space normals), `full` its texture at the layout's c_r = 1 (RGB).
struct MaterialMap {
  int image = -1;  // glTF image index in the layout's file (-1: re-baked from the reference's)
  atlas::RebakeRole kind = atlas::RebakeRole::Color;
  Image full;
};

struct LayoutMesh {
  std::string name, file;
  std::string texture_source;  // "original", "rebaked", "own"
  std::vector<float> positions;  // x y z per vertex
  std::vector<uint32_t> indices;  // 3 per triangle
  std::vector<float> uvs;        // u v per vertex, KHR_texture_transform applied
  Image full;                    // RGB, the layout's full texture
  bool repeat = true;            // the sampler wraps (REPEAT) rather than clamps
  int image = -1;                // glTF image index of the driving texture
  double uv_area = 0;            // sum |uv triangle area|, unit square
  double area3d = 0;             // sum |triangle area|
  // Lit shading (lit.h), filled by extract_layout with `lit`: per vertex normals (3, empty:
  // flat) and glTF tangents (4, empty: derived from the UVs when lit), the material of each
  // triangle, the materials and their maps. `lit_problem` says why this layout cannot be
  // lit ("" when it can).
  std::vector<float> normals, tangents;
  std::vector<uint32_t> triangle_material;
  std::vector<LitMaterial> materials;
  std::vector<MaterialMap> maps;
  std::string lit_problem;
};

// True when a material of `file` has a normalTexture: the assets --shading auto lights.
bool has_normal_map(const io::GltfFile& file);

// The driving texture (the base colour image sampled by the most triangles, else any
// sampled image) and every triangle primitive that samples it. With `lit`, also what lit
// shading needs (see LayoutMesh): maps sampled through another UV set or transform than
// the driving texture's, and normal maps with fewer than 3 channels, leave lit_problem set
// (the caller falls back or fails, saying so). Throws InputError.
// `image` >= 0: that image instead (InputError when no triangle primitive samples it).
LayoutMesh extract_layout(const io::GltfFile& file, const std::string& name, bool lit = false, int image = -1);

// Per triangle uv area and 3-D area.
double uv_area(const std::vector<float>& uvs, const std::vector<uint32_t>& indices, size_t t);
double area3d(const std::vector<float>& positions, const std::vector<uint32_t>& indices, size_t t);

// True when `b` has the same triangles as `a` in the same order (corner positions within
// `tolerance`).
bool same_triangles(const LayoutMesh& a, const LayoutMesh& b, double tolerance);

// The reference texture re-baked into `target`'s UVs (triangles corresponding one to one
// with `reference`'s) at width x height, by atlas::rebake; `method` names it for reports.
Image rebake_from(const LayoutMesh& reference, const LayoutMesh& target, uint32_t width, uint32_t height,
                  std::string* method = nullptr);
// The same for one of the reference's maps (its kind decides colour, data or normal
// re-bake; normals are rotated into the new UV frame only when `target` derives its
// tangents from its UVs, as reparam does).
Image rebake_map_from(const LayoutMesh& reference, const MaterialMap& map, const LayoutMesh& target, uint32_t width,
                      uint32_t height);

// The isometric layout of `reference` (eval.cpp, "Layouts"): new UVs per vertex in [0,1] and the
// aspect (width / height) its texture should have. `info` gets charts, flattened charts,
// kept charts, seconds.
std::vector<float> isometric_uvs(const LayoutMesh& reference, double* aspect, nlohmann::ordered_json* info);

}  // namespace uvpress::eval::detail
