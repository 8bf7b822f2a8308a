#include "pipeline/demo_asset.h"

#include "core/image.h"
#include "io/gltf_append.h"
#include "io/image_io.h"

#include <cmath>
#include <cstring>

namespace uvpress::pipeline {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Integer hash -> [0,1): deterministic noise without a random engine.
double hash01(uint32_t x, uint32_t y, uint32_t seed) {
  uint32_t h = x * 0x8da6b343u ^ y * 0xd8163841u ^ seed * 0xcb1ab31fu;
  h ^= h >> 13, h *= 0x5bd1e995u, h ^= h >> 15;
  return (h & 0xffffff) / double(0x1000000);
}

// The texture, as [0,1] sRGB-encoded RGB. Left: two flat colours; middle: a smooth
// gradient; right: fine checks, thin stripes and noise; plus a detailed badge in the flat
// area. The perceptual loss should let the flat and smooth parts shrink and keep the rest.
void shade(double u, double v, int size, double rgb[3]) {
  if (u < 0.38) {  // flat colours, split by one soft diagonal edge
    bool upper = v > 0.45 + 0.1 * u;
    rgb[0] = upper ? 0.85 : 0.20, rgb[1] = upper ? 0.55 : 0.35, rgb[2] = upper ? 0.20 : 0.60;
    double bx = (u - 0.19) / 0.08, by = (v - 0.22) / 0.08;  // badge: fine rings inside a disk
    double r = std::sqrt(bx * bx + by * by);
    if (r < 1) {
      double ring = 0.5 + 0.5 * std::cos(r * 18 * kPi);
      rgb[0] = 0.95 * ring, rgb[1] = 0.9 * ring, rgb[2] = 0.2 + 0.7 * (1 - ring);
    }
  } else if (u < 0.62) {  // smooth gradient
    double s = (u - 0.38) / 0.24;
    rgb[0] = 0.2 + 0.6 * s, rgb[1] = 0.35 + 0.3 * std::sin(kPi * v), rgb[2] = 0.6 - 0.4 * s;
  } else {  // fine detail
    int px = int(u * size), py = int(v * size);
    double check = ((px / 4 + py / 4) % 2) ? 0.9 : 0.1;
    double stripe = 0.5 + 0.5 * std::sin(2 * kPi * (u * 96 + v * 40));
    double noise = hash01(uint32_t(px), uint32_t(py), 7);
    double band = v < 0.33 ? check : v < 0.66 ? stripe : noise;
    rgb[0] = 0.15 + 0.8 * band, rgb[1] = 0.1 + 0.7 * band * band, rgb[2] = 0.25 + 0.5 * (1 - band);
  }
}

}  // namespace

io::GltfFile make_demo_asset(const DemoOptions& o) {
  const int n = o.grid;
  std::vector<float> positions, normals, uvs;
  std::vector<uint16_t> indices;
  // A sheet bent around a vertical axis (90 degrees of arc) with a bump: curved in both
  // directions, so no single planar projection of it is isometric.
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      double s = double(i) / n, t = double(j) / n;
      double theta = (s - 0.5) * kPi * 0.5, bump = 0.25 * std::exp(-((s - 0.5) * (s - 0.5) + (t - 0.5) * (t - 0.5)) / 0.05);
      double r = 1.0 + bump;
      positions.insert(positions.end(), {float(r * std::sin(theta)), float(t - 0.5) * 1.6f, float(r * std::cos(theta))});
      uvs.insert(uvs.end(), {float(s), float(1 - t)});
    }
  // Normals by central differences of the parametric surface.
  normals.resize(positions.size());
  auto p = [&](int i, int j, int c) { return double(positions[size_t(3 * (j * (n + 1) + i) + c)]); };
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      int i0 = std::max(i - 1, 0), i1 = std::min(i + 1, n), j0 = std::max(j - 1, 0), j1 = std::min(j + 1, n);
      double du[3], dv[3];
      for (int c = 0; c < 3; ++c) du[c] = p(i1, j, c) - p(i0, j, c), dv[c] = p(i, j1, c) - p(i, j0, c);
      double nx = dv[1] * du[2] - dv[2] * du[1], ny = dv[2] * du[0] - dv[0] * du[2], nz = dv[0] * du[1] - dv[1] * du[0];
      double len = std::sqrt(nx * nx + ny * ny + nz * nz);
      float* out = &normals[size_t(3 * (j * (n + 1) + i))];
      out[0] = float(nx / len), out[1] = float(ny / len), out[2] = float(nz / len);
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      uint16_t a = uint16_t(j * (n + 1) + i), b = uint16_t(a + 1), c = uint16_t(a + n + 1), d = uint16_t(c + 1);
      // Counter-clockwise seen from outside (+z at the middle).
      indices.insert(indices.end(), {a, b, d, a, d, c});
    }

  io::GltfFile file;
  file.path = "demo.glb";
  tinygltf::Model& m = file.model;
  m.asset.version = "2.0";
  m.asset.generator = "uvpress demo";
  m.buffers.resize(1);
  int pos = io::append_float_accessor(m, positions, TINYGLTF_TYPE_VEC3);
  int nor = io::append_float_accessor(m, normals, TINYGLTF_TYPE_VEC3);
  int tex = io::append_float_accessor(m, uvs, TINYGLTF_TYPE_VEC2);
  int idx = io::append_index_accessor(m, indices);

  tinygltf::Primitive prim;
  prim.attributes = {{"POSITION", pos}, {"NORMAL", nor}, {"TEXCOORD_0", tex}};
  prim.indices = idx;
  prim.material = 0;
  prim.mode = TINYGLTF_MODE_TRIANGLES;
  tinygltf::Mesh mesh;
  mesh.name = "sheet";
  mesh.primitives.push_back(prim);
  m.meshes.push_back(mesh);
  tinygltf::Node node;
  node.name = "sheet";
  node.mesh = 0;
  m.nodes.push_back(node);
  tinygltf::Scene scene;
  scene.nodes = {0};
  m.scenes.push_back(scene);
  m.defaultScene = 0;

  tinygltf::Material mat;
  mat.name = "demo";
  mat.pbrMetallicRoughness.baseColorTexture.index = 0;
  mat.pbrMetallicRoughness.metallicFactor = 0.0;
  mat.pbrMetallicRoughness.roughnessFactor = 0.8;
  m.materials.push_back(mat);
  tinygltf::Sampler sampler;
  sampler.magFilter = TINYGLTF_TEXTURE_FILTER_LINEAR;
  sampler.minFilter = TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_LINEAR;
  sampler.wrapS = sampler.wrapT = TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
  m.samplers.push_back(sampler);
  tinygltf::Texture texture;
  texture.sampler = 0;
  texture.source = 0;
  m.textures.push_back(texture);
  tinygltf::Image image;
  image.name = "demo_basecolor";
  image.mimeType = "image/png";
  m.images.push_back(image);

  Image pixels;
  pixels.width = pixels.height = uint32_t(o.texture_size);
  pixels.channels = 3;
  pixels.pixels.resize(size_t(o.texture_size) * o.texture_size * 3);
  for (int y = 0; y < o.texture_size; ++y)
    for (int x = 0; x < o.texture_size; ++x) {
      double rgb[3];
      shade((x + 0.5) / o.texture_size, (y + 0.5) / o.texture_size, o.texture_size, rgb);
      for (int c = 0; c < 3; ++c) pixels.at(uint32_t(x), uint32_t(y), uint32_t(c)) = float(rgb[c]);
    }
  file.image_bytes.push_back(io::encode_image(pixels, "png"));
  return file;
}

}  // namespace uvpress::pipeline
