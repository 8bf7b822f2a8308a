// A test asset shared by the lit-shading tests (tests/eval/test_lit.cpp) and the eval CLI's
// (tests/cli/test_eval.cpp): a bent sheet whose detail lives in its normal map.
#pragma once

#include "core/image.h"
#include "io/gltf_append.h"
#include "io/gltf_io.h"
#include "io/image_io.h"

#include <cmath>
#include <cstdint>
#include <vector>

namespace uvpress::test {

// A sheet bent through 90 degrees around the vertical axis (so the fixed lights graze
// parts of it in every view), UVs over [0,1]^2, smooth normals; a flat grey base colour
// and, with `normal_map`, a tangent-space normal map of bumps 2 texels wide (a height
// field h = sin(2 pi x / 4) sin(2 pi y / 4) in texels): all the asset's detail lives there.
inline io::GltfFile bumpy_sheet(bool normal_map, int texture = 128, int grid = 24) {
  constexpr double kPi = 3.14159265358979323846;
  std::vector<float> positions, normals, uvs;
  std::vector<uint16_t> indices;
  for (int j = 0; j <= grid; ++j)
    for (int i = 0; i <= grid; ++i) {
      const double s = double(i) / grid, t = double(j) / grid, theta = (s - 0.5) * kPi * 0.5;
      positions.insert(positions.end(), {float(std::sin(theta)), float(t - 0.5) * 1.6f, float(std::cos(theta))});
      normals.insert(normals.end(), {float(std::sin(theta)), 0.0f, float(std::cos(theta))});
      uvs.insert(uvs.end(), {float(s), float(1 - t)});
    }
  for (int j = 0; j < grid; ++j)
    for (int i = 0; i < grid; ++i) {
      const uint16_t a = uint16_t(j * (grid + 1) + i), b = uint16_t(a + 1), c = uint16_t(a + grid + 1), d = uint16_t(c + 1);
      indices.insert(indices.end(), {a, b, d, a, d, c});
    }
  io::GltfFile file;
  file.path = normal_map ? "bumpy.glb" : "flat.glb";
  tinygltf::Model& m = file.model;
  m.asset.version = "2.0";
  m.buffers.resize(1);
  tinygltf::Primitive prim;
  prim.attributes = {{"POSITION", io::append_float_accessor(m, positions, TINYGLTF_TYPE_VEC3)},
                     {"NORMAL", io::append_float_accessor(m, normals, TINYGLTF_TYPE_VEC3)},
                     {"TEXCOORD_0", io::append_float_accessor(m, uvs, TINYGLTF_TYPE_VEC2)}};
  prim.indices = io::append_index_accessor(m, indices);
  prim.material = 0;
  prim.mode = TINYGLTF_MODE_TRIANGLES;
  tinygltf::Mesh mesh;
  mesh.primitives.push_back(prim);
  m.meshes.push_back(mesh);
  tinygltf::Node node;
  node.mesh = 0;
  m.nodes.push_back(node);
  m.scenes.push_back(tinygltf::Scene());
  m.scenes[0].nodes = {0};
  m.defaultScene = 0;
  tinygltf::Material mat;
  mat.pbrMetallicRoughness.baseColorTexture.index = 0;
  mat.pbrMetallicRoughness.metallicFactor = 0.0;
  mat.pbrMetallicRoughness.roughnessFactor = 0.6;
  if (normal_map) mat.normalTexture.index = 1;
  m.materials.push_back(mat);
  tinygltf::Sampler sampler;
  sampler.wrapS = sampler.wrapT = TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
  m.samplers.push_back(sampler);
  auto add_image = [&](const Image& img, const char* name) {
    tinygltf::Texture tex;
    tex.sampler = 0, tex.source = int(m.images.size());
    m.textures.push_back(tex);
    tinygltf::Image image;
    image.name = name, image.mimeType = "image/png";
    m.images.push_back(image);
    file.image_bytes.push_back(io::encode_image(img, "png"));
  };
  Image base;
  base.width = base.height = uint32_t(texture), base.channels = 3;
  base.pixels.assign(size_t(texture) * texture * 3, 0.6f);
  add_image(base, "base");
  if (normal_map) {
    Image n = base;
    const double a = 0.9, k = 2 * kPi / 4;  // bump slope, period 4 texels
    for (int y = 0; y < texture; ++y)
      for (int x = 0; x < texture; ++x) {
        const double X = x + 0.5, Y = y + 0.5;
        // Image y runs down, the normal map's +Y up: dh/d(up) = -dh/dy.
        const double hx = a * std::cos(k * X) * std::sin(k * Y), hy = -a * std::sin(k * X) * std::cos(k * Y);
        double v[3] = {-hx, -hy, 1};
        const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        for (int c = 0; c < 3; ++c) n.at(uint32_t(x), uint32_t(y), uint32_t(c)) = float(std::round((v[c] / l * 0.5 + 0.5) * 255) / 255);
      }
    add_image(n, "normal");
  }
  return file;
}

}  // namespace uvpress::test
