// Lit shading for eval (issue 14, item 5): the views lit by a fixed light rig through the
// asset's normal, occlusion, metallic-roughness and emissive maps, so that eval's q sees
// those maps too (the unlit q reads the base colour's luminance only).
//
// How a lit view is made, without touching the engine: every map the lighting needs is
// rendered by engine::render_mesh through the layout's UVs with the same cameras and
// filter as the unlit views (each map its own texture, 3 channels), and the lighting runs
// here on the host, pixel by pixel: the covered triangle (render_mesh's coverage) and the
// camera give the pixel's perspective-correct barycentrics on that triangle; they
// interpolate the vertex normal and tangent frame; the sampled tangent-space normal
// perturbs it; a metallic-roughness BRDF (glTF 2.0 Appendix B: Lambert diffuse, GGX with
// Smith height-correlated visibility and Schlick Fresnel) under the rig gives linear
// radiance, which is clamped to [0,1], sRGB-encoded and reduced to luminance exactly like
// the unlit path (Y = 0.299 R + 0.587 G + 0.114 B on the stored values, GMSD step 1).
//
// Everything here is per pixel with no reduction, so results do not depend on threads.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace uvpress::eval {

// Which q eval reports as `q` (and reparam's guard and bench quality use): unlit (the
// driving texture's luminance), lit (this file), or auto: lit when a material of the
// reference has a normalTexture (the maps eval would otherwise not see), else unlit, so
// assets without normal maps keep their unlit figures bit for bit.
enum class Shading { Auto, Unlit, Lit };
const char* to_string(Shading shading);
std::optional<Shading> parse_shading(std::string_view text);

// A directional light: unit direction toward the light (world space, the asset's own
// frame, y up as glTF) and the irradiance it gives a surface facing it (linear units in
// which a white Lambert surface facing a light of irradiance pi has radiance 1).
struct DirectionalLight {
  std::array<double, 3> direction;
  double irradiance;
};

// The fixed rig: a key light above front-right, a weaker fill from the left, a rim light
// from behind and above, plus ambient (scaled by occlusion). Directions are fixed in the
// asset's frame rather than per camera, so the 20 views see one consistently lit object
// (as a viewer's default environment does) and every view has lit and grazing parts:
// grazing light is what makes bumps in a normal map visible.
struct LightRig {
  std::vector<DirectionalLight> lights;
  double ambient = 0;
};
LightRig default_light_rig();

// A material as lighting reads it (glTF 2.0 defaults where a map or factor is absent).
// Map fields index the layout's map list (-1: none); each map is rendered with 3 channels.
struct LitMaterial {
  std::array<double, 4> base_color_factor{1, 1, 1, 1};
  int base_color_map = -1;      // sRGB RGB
  int normal_map = -1;          // tangent-space RGB = (n + 1) / 2
  double normal_scale = 1;      // normalTexture.scale (x and y of n)
  int occlusion_map = -1;       // R channel
  double occlusion_strength = 1;
  int metallic_roughness_map = -1;  // G roughness, B metallic
  double roughness_factor = 1, metallic_factor = 1;
  int emissive_map = -1;  // sRGB RGB
  std::array<double, 3> emissive_factor{0, 0, 0};
};

// The surface at one pixel: what the maps give (values as stored, fp32 samples) with the
// material's factors applied by shade_pixel.
struct SampledMaps {
  const float* base_color = nullptr;  // 3 values, or null (factor only)
  const float* normal = nullptr;
  const float* occlusion_rgb = nullptr;
  const float* metallic_roughness = nullptr;
  const float* emissive = nullptr;
};

// Per-vertex tangents (x y z w, glTF TANGENT convention: bitangent = cross(N, T) w) from
// positions, UVs and per-vertex normals: the Lengyel / sample-viewer frame, T along +u and
// the bitangent toward -v (glTF normal maps: +Y up in the image, UV v down), per-triangle
// frames summed unnormalized (area-weighted) in triangle order, then Gram-Schmidt against
// the normal. w = -1 where the UVs are mirrored. Degenerate UVs get any unit tangent
// perpendicular to the normal. `normals` may be empty: face normals (area-weighted) then.
// What a renderer derives when a mesh has no TANGENT (MikkTSpace agrees for smooth,
// unmirrored charts), and the frame atlas::rebake's normal rotation assumes.
std::vector<float> vertex_tangents(const std::vector<float>& positions, const std::vector<float>& uvs,
                                   const std::vector<uint32_t>& indices, const std::vector<float>& normals);

// The eye of a perspective camera (row-major clip = M (x, y, z, 1)): the point where clip
// x, y and w vanish.
std::array<double, 3> camera_eye(const std::array<float, 16>& camera);

// Clip coordinates of point p (x y z) under the row-major view-projection m, in double.
std::array<double, 4> clip_of(const std::array<float, 16>& m, const float* p);

// Perspective-correct barycentrics of the centre of pixel (i, j) (row 0 on top) of a
// `width` x `height` view on the triangle p0 p1 p2 (world space): the point where the
// pixel's ray meets the triangle's plane, as weights of the three corners (2-D weights in
// NDC divided by clip w, renormalized: the same point as intersecting the ray). Weights are
// not clamped (a pixel centre the rasterizer's snapped vertices let in may lie a hair
// outside). Returns false when the triangle is degenerate on screen.
bool pixel_barycentrics(const std::array<float, 16>& camera, const float* p0, const float* p1, const float* p2,
                        uint32_t i, uint32_t j, uint32_t width, uint32_t height, double weights[3]);

// Linear RGB radiance of one surface point: n the shading normal (unit, world), v the unit
// vector toward the eye, base colour (linear, factor applied), occlusion in [0,1],
// perceptual roughness and metallic in [0,1], emissive (linear). glTF 2.0 Appendix B BRDF
// under `rig`, ambient x occlusion x (diffuse colour + F0).
std::array<double, 3> shade(const LightRig& rig, const std::array<double, 3>& n, const std::array<double, 3>& v,
                            const std::array<double, 3>& base, double occlusion, double roughness, double metallic,
                            const std::array<double, 3>& emissive);

// The geometry a layout is lit with: vertex normals (3 per vertex; empty: flat face
// normals, as glTF asks when NORMAL is absent) and tangents (4 per vertex).
struct LitSurface {
  const std::vector<float>* positions = nullptr;
  const std::vector<uint32_t>* indices = nullptr;
  std::vector<float> normals;   // per vertex, or empty
  std::vector<float> tangents;  // per vertex, x y z w
  const std::vector<uint32_t>* triangle_material = nullptr;  // per triangle, into materials
  const std::vector<LitMaterial>* materials = nullptr;
};

// One lit view's luminance (width x height, row 0 on top; 0 where coverage is empty, as
// the unlit renders' background): for every covered pixel, the triangle's frame at the
// pixel's barycentrics (flipped toward the eye for back faces: double-sided, as glTF's
// doubleSided and render_mesh's no culling), perturbed by the normal map, shaded, clamped,
// sRGB-encoded, luminance. `maps[k]` is map k's render of this view (3 floats a pixel).
void lit_luminance(const LitSurface& surface, const LightRig& rig, const std::array<float, 16>& camera, uint32_t width,
                   uint32_t height, const uint32_t* coverage, const std::vector<const float*>& maps, float* out);

}  // namespace uvpress::eval
