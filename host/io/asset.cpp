#include "io/asset.h"
#include "io/vertex_attribute.h"

#include "core/error.h"

#include <cmath>
#include <cstring>
#include <filesystem>

namespace uvpress::io {

const char* to_string(TextureRole r) {
  switch (r) {
    case TextureRole::BaseColor: return "baseColor";
    case TextureRole::MetallicRoughness: return "metallicRoughness";
    case TextureRole::Normal: return "normal";
    case TextureRole::Occlusion: return "occlusion";
    case TextureRole::Emissive: return "emissive";
    case TextureRole::Other: return "other";
  }
  return "other";
}

ColorSpace color_space_of(TextureRole r) {
  return (r == TextureRole::BaseColor || r == TextureRole::Emissive) ? ColorSpace::Srgb : ColorSpace::Linear;
}

std::array<float, 2> TextureTransform::apply(float u, float v) const {
  if (!present) return {u, v};
  // KHR_texture_transform: translation * rotation * scale, rotation counter-clockwise in UV.
  float su = u * scale[0], sv = v * scale[1];
  float c = std::cos(rotation), s = std::sin(rotation);
  return {c * su + s * sv + offset[0], -s * su + c * sv + offset[1]};
}

namespace {

class Reader {
 public:
  Reader(const GltfFile& f) : file_(f), m_(f.model) {}

  [[noreturn]] void fail(const std::string& reason) const { throw InputError(file_.path, reason); }

  // Decodes accessor `index` into floats, `width` components per element, applying
  // normalization and sparse substitution. Every byte it touches is bounds-checked.
  std::vector<float> floats(int index, int width, const std::string& what, bool* normalized = nullptr) const {
    const tinygltf::Accessor& a = accessor(index, what);
    if (tinygltf::GetNumComponentsInType(uint32_t(a.type)) != width)
      fail(what + ": accessor " + std::to_string(index) + " has the wrong type");
    if (normalized) *normalized = a.normalized;
    // Bounds before the allocation: a declared count must not size memory on its own.
    if (a.count > kMaxElements) fail(what + ": accessor " + std::to_string(index) + " declares an implausible count (" + std::to_string(a.count) + ")");
    if (a.bufferView >= 0) {
      size_t stride, size = component_size(a.componentType);
      if (size == 0) fail(what + ": unsupported component type " + std::to_string(a.componentType));
      span(a.bufferView, a.byteOffset, a.count, size * size_t(width), &stride, what);
    }
    std::vector<float> out(a.count * size_t(width), 0.0f);
    if (a.bufferView >= 0) read_elements(a, a.bufferView, a.byteOffset, a.count, width, what, out.data());
    if (a.sparse.isSparse) {
      const auto& s = a.sparse;
      if (s.count < 0 || size_t(s.count) > a.count) fail(what + ": sparse count out of range");
      std::vector<uint32_t> idx = integers(s.indices.bufferView, size_t(s.indices.byteOffset), size_t(s.count),
                                           s.indices.componentType, what + " sparse indices");
      std::vector<float> values(size_t(s.count) * size_t(width));
      tinygltf::Accessor va = a;
      read_elements(va, s.values.bufferView, size_t(s.values.byteOffset), size_t(s.count), width, what,
                    values.data());
      for (size_t k = 0; k < idx.size(); ++k) {
        if (idx[k] >= a.count) fail(what + ": sparse index out of range");
        std::memcpy(&out[idx[k] * size_t(width)], &values[k * size_t(width)], sizeof(float) * size_t(width));
      }
    }
    return out;
  }

  std::vector<uint32_t> indices(int index, const std::string& what) const {
    const tinygltf::Accessor& a = accessor(index, what);
    if (a.type != TINYGLTF_TYPE_SCALAR) fail(what + ": index accessor is not SCALAR");
    if (a.bufferView < 0 || a.sparse.isSparse) fail(what + ": index accessor without a plain bufferView");
    return integers(a.bufferView, a.byteOffset, a.count, a.componentType, what);
  }

  const tinygltf::Model& model() const { return m_; }

 private:
  static constexpr size_t kMaxElements = size_t(1) << 28;  // 268M vertices: beyond any real asset

  static size_t component_size(int ct) {
    return ct == TINYGLTF_COMPONENT_TYPE_FLOAT                                                          ? 4
           : (ct == TINYGLTF_COMPONENT_TYPE_SHORT || ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) ? 2
           : (ct == TINYGLTF_COMPONENT_TYPE_BYTE || ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE)   ? 1
                                                                                                   : 0;
  }

  const tinygltf::Accessor& accessor(int index, const std::string& what) const {
    if (index < 0 || size_t(index) >= m_.accessors.size())
      fail(what + ": accessor " + std::to_string(index) + " does not exist");
    return m_.accessors[size_t(index)];
  }

  // The bytes [offset, offset + stride*(count-1) + element) of bufferView `view`.
  const uint8_t* span(int view_index, size_t offset, size_t count, size_t element, size_t* stride,
                      const std::string& what) const {
    if (view_index < 0 || size_t(view_index) >= m_.bufferViews.size())
      fail(what + ": bufferView " + std::to_string(view_index) + " does not exist");
    const auto& view = m_.bufferViews[size_t(view_index)];
    if (view.buffer < 0 || size_t(view.buffer) >= m_.buffers.size()) fail(what + ": buffer does not exist");
    const auto& data = m_.buffers[size_t(view.buffer)].data;
    *stride = view.byteStride ? view.byteStride : element;
    if (count == 0) return data.data();
    // Overflow-safe: each term is checked against the view before the next is added.
    if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
      fail(what + ": bufferView " + std::to_string(view_index) + " lies outside its buffer");
    if (*stride < element || (count - 1) > (view.byteLength / *stride) || offset > view.byteLength ||
        (count - 1) * *stride + element > view.byteLength - offset)
      fail(what + ": accessor reads past the end of bufferView " + std::to_string(view_index));
    return data.data() + view.byteOffset + offset;
  }

  void read_elements(const tinygltf::Accessor& a, int view, size_t offset, size_t count, int width,
                     const std::string& what, float* out) const {
    int ct = a.componentType;
    size_t size = ct == TINYGLTF_COMPONENT_TYPE_FLOAT ? 4
                  : (ct == TINYGLTF_COMPONENT_TYPE_SHORT || ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) ? 2
                  : (ct == TINYGLTF_COMPONENT_TYPE_BYTE || ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE)   ? 1
                                                                                                          : 0;
    if (size == 0) fail(what + ": unsupported component type " + std::to_string(ct));
    size_t stride;
    const uint8_t* p = span(view, offset, count, size * size_t(width), &stride, what);
    for (size_t i = 0; i < count; ++i)
      for (int c = 0; c < width; ++c) {
        const uint8_t* q = p + i * stride + size_t(c) * size;
        float v;
        switch (ct) {
          case TINYGLTF_COMPONENT_TYPE_FLOAT: std::memcpy(&v, q, 4); break;
          case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: v = a.normalized ? *q / 255.0f : *q; break;
          case TINYGLTF_COMPONENT_TYPE_BYTE: {
            float s = float(int8_t(*q));
            v = a.normalized ? std::max(s / 127.0f, -1.0f) : s;
            break;
          }
          case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            uint16_t s;
            std::memcpy(&s, q, 2);
            v = a.normalized ? s / 65535.0f : s;
            break;
          }
          default: {
            int16_t s;
            std::memcpy(&s, q, 2);
            v = a.normalized ? std::max(s / 32767.0f, -1.0f) : float(s);
          }
        }
        out[i * size_t(width) + size_t(c)] = v;
      }
  }

  std::vector<uint32_t> integers(int view, size_t offset, size_t count, int ct, const std::string& what) const {
    size_t size = ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT     ? 4
                  : ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ? 2
                  : ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE  ? 1
                                                                 : 0;
    if (size == 0) fail(what + ": indices must be unsigned byte, short or int");
    size_t stride;
    const uint8_t* p = span(view, offset, count, size, &stride, what);
    std::vector<uint32_t> out(count);
    for (size_t i = 0; i < count; ++i) {
      uint32_t v = 0;
      std::memcpy(&v, p + i * stride, size);  // little-endian host
      out[i] = v;
    }
    return out;
  }

  const GltfFile& file_;
  const tinygltf::Model& m_;
};

// Triangle list from a primitive's mode; strips and fans are expanded keeping winding.
std::vector<uint32_t> to_triangles(const std::vector<uint32_t>& idx, int mode) {
  std::vector<uint32_t> t;
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    t.assign(idx.begin(), idx.begin() + long(idx.size() / 3 * 3));
  } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
    for (size_t i = 0; i + 2 < idx.size(); ++i) {
      if (i % 2 == 0) t.insert(t.end(), {idx[i], idx[i + 1], idx[i + 2]});
      else t.insert(t.end(), {idx[i + 1], idx[i], idx[i + 2]});
    }
  } else if (mode == TINYGLTF_MODE_TRIANGLE_FAN) {
    for (size_t i = 1; i + 1 < idx.size(); ++i) t.insert(t.end(), {idx[0], idx[i], idx[i + 1]});
  }
  return t;
}

float number(const tinygltf::Value& v, float fallback) { return v.IsNumber() ? float(v.GetNumberAsDouble()) : fallback; }

TextureTransform transform_of(const tinygltf::ExtensionMap& ext, int* tex_coord) {
  TextureTransform t;
  auto it = ext.find("KHR_texture_transform");
  if (it == ext.end() || !it->second.IsObject()) return t;
  const tinygltf::Value& v = it->second;
  t.present = true;
  if (v.Has("offset") && v.Get("offset").ArrayLen() == 2)
    t.offset = {number(v.Get("offset").Get(0), 0), number(v.Get("offset").Get(1), 0)};
  if (v.Has("scale") && v.Get("scale").ArrayLen() == 2)
    t.scale = {number(v.Get("scale").Get(0), 1), number(v.Get("scale").Get(1), 1)};
  if (v.Has("rotation")) t.rotation = number(v.Get("rotation"), 0);
  if (v.Has("texCoord") && v.Get("texCoord").IsInt()) *tex_coord = v.Get("texCoord").GetNumberAsInt();
  return t;
}

bool repeats(int wrap) { return wrap == TINYGLTF_TEXTURE_WRAP_REPEAT || wrap == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT; }

}  // namespace

Asset build_asset(const GltfFile& file) {
  Reader r(file);
  const tinygltf::Model& m = r.model();
  Asset asset;

  for (size_t mi = 0; mi < m.meshes.size(); ++mi) {
    for (size_t pi = 0; pi < m.meshes[mi].primitives.size(); ++pi) {
      const auto& gp = m.meshes[mi].primitives[pi];
      const std::string what = "mesh " + std::to_string(mi) + " primitive " + std::to_string(pi);
      int mode = gp.mode < 0 ? TINYGLTF_MODE_TRIANGLES : gp.mode;
      if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
          mode != TINYGLTF_MODE_TRIANGLE_FAN) {
        ++asset.skipped_primitives;
        continue;
      }
      if (gp.extensions.count("KHR_draco_mesh_compression"))
        r.fail(what + ": Draco-compressed geometry is not supported (decompress it first)");
      auto pos = gp.attributes.find("POSITION");
      if (pos == gp.attributes.end()) r.fail(what + ": no POSITION attribute");
      Primitive p;
      p.mesh = int(mi), p.primitive = int(pi), p.mesh_name = m.meshes[mi].name, p.material = gp.material;
      if (p.material >= int(m.materials.size())) r.fail(what + ": material " + std::to_string(p.material) + " does not exist");
      p.positions = r.floats(pos->second, 3, what + " POSITION");
      for (float v : p.positions)
        if (!std::isfinite(v)) r.fail(what + ": POSITION has non-finite values");
      const size_t n = p.vertex_count();
      std::vector<uint32_t> idx;
      if (gp.indices >= 0) {
        idx = r.indices(gp.indices, what + " indices");
        for (uint32_t i : idx)
          if (i >= n) r.fail(what + ": index " + std::to_string(i) + " out of range (" + std::to_string(n) + " vertices)");
      } else {
        idx.resize(n);
        for (size_t i = 0; i < n; ++i) idx[i] = uint32_t(i);
      }
      p.indices = to_triangles(idx, mode);
      for (const auto& [name, accessor] : gp.attributes) {
        if (name.rfind("TEXCOORD_", 0) != 0) continue;
        char* end = nullptr;
        long set = std::strtol(name.c_str() + 9, &end, 10);
        if (*end != '\0' || set < 0 || set > 31) continue;
        if (p.uv_sets.size() <= size_t(set)) p.uv_sets.resize(size_t(set) + 1);
        UvSet& uv = p.uv_sets[size_t(set)];
        uv.uv = r.floats(accessor, 2, what + " " + name, &uv.normalized);
        uv.component_type = m.accessors[size_t(accessor)].componentType;
        if (uv.uv.size() != 2 * n) r.fail(what + ": " + name + " count differs from POSITION count");
        uv.min = {INFINITY, INFINITY}, uv.max = {-INFINITY, -INFINITY};
        for (size_t i = 0; i < n; ++i)
          for (int c = 0; c < 2; ++c) {
            float v = uv.uv[2 * i + size_t(c)];
            if (!std::isfinite(v)) r.fail(what + ": " + name + " has non-finite values");
            uv.min[size_t(c)] = std::min(uv.min[size_t(c)], v), uv.max[size_t(c)] = std::max(uv.max[size_t(c)], v);
          }
        if (n == 0) uv.min = uv.max = {0, 0};
      }
      asset.primitives.push_back(std::move(p));
    }
  }

  // Images and who samples them.
  asset.images.resize(m.images.size());
  for (size_t i = 0; i < m.images.size(); ++i) {
    AssetImage& img = asset.images[i];
    const auto& gi = m.images[i];
    img.index = int(i);
    img.mime = gi.mimeType;
    if (!gi.name.empty()) img.name = gi.name;
    else if (!gi.uri.empty() && gi.uri.rfind("data:", 0) != 0) img.name = std::filesystem::path(gi.uri).filename().string();
    else img.name = "image " + std::to_string(i);
  }
  for (size_t mat = 0; mat < m.materials.size(); ++mat) {
    const auto& gm = m.materials[mat];
    struct Slot {
      const char* name;
      TextureRole role;
      int index, tex_coord;
      const tinygltf::ExtensionMap* ext;
    };
    const Slot slots[] = {
        {"pbrMetallicRoughness.baseColorTexture", TextureRole::BaseColor, gm.pbrMetallicRoughness.baseColorTexture.index,
         gm.pbrMetallicRoughness.baseColorTexture.texCoord, &gm.pbrMetallicRoughness.baseColorTexture.extensions},
        {"pbrMetallicRoughness.metallicRoughnessTexture", TextureRole::MetallicRoughness,
         gm.pbrMetallicRoughness.metallicRoughnessTexture.index, gm.pbrMetallicRoughness.metallicRoughnessTexture.texCoord,
         &gm.pbrMetallicRoughness.metallicRoughnessTexture.extensions},
        {"normalTexture", TextureRole::Normal, gm.normalTexture.index, gm.normalTexture.texCoord,
         &gm.normalTexture.extensions},
        {"occlusionTexture", TextureRole::Occlusion, gm.occlusionTexture.index, gm.occlusionTexture.texCoord,
         &gm.occlusionTexture.extensions},
        {"emissiveTexture", TextureRole::Emissive, gm.emissiveTexture.index, gm.emissiveTexture.texCoord,
         &gm.emissiveTexture.extensions},
    };
    for (const Slot& slot : slots) {
      if (slot.index < 0) continue;
      const std::string what = "material " + std::to_string(mat) + " " + slot.name;
      if (size_t(slot.index) >= m.textures.size()) r.fail(what + ": texture " + std::to_string(slot.index) + " does not exist");
      const auto& tex = m.textures[size_t(slot.index)];
      if (tex.source < 0) continue;  // e.g. only an extension source (KTX2 via KHR_texture_basisu)
      if (size_t(tex.source) >= m.images.size()) r.fail(what + ": image " + std::to_string(tex.source) + " does not exist");
      int wrap_s = TINYGLTF_TEXTURE_WRAP_REPEAT, wrap_t = TINYGLTF_TEXTURE_WRAP_REPEAT;
      if (tex.sampler >= 0) {
        if (size_t(tex.sampler) >= m.samplers.size()) r.fail(what + ": sampler does not exist");
        wrap_s = m.samplers[size_t(tex.sampler)].wrapS, wrap_t = m.samplers[size_t(tex.sampler)].wrapT;
      }
      int tex_coord = slot.tex_coord;
      TextureTransform transform = transform_of(*slot.ext, &tex_coord);
      AssetImage& img = asset.images[size_t(tex.source)];
      for (size_t pi = 0; pi < asset.primitives.size(); ++pi) {
        const Primitive& p = asset.primitives[pi];
        if (p.material != int(mat)) continue;
        ImageUse use;
        use.material = int(mat), use.role = slot.role, use.slot = slot.name, use.texture = slot.index;
        use.primitive = int(pi), use.tex_coord = tex_coord, use.transform = transform;
        use.wrap_s = wrap_s, use.wrap_t = wrap_t;
        if (tex_coord < 0 || size_t(tex_coord) >= p.uv_sets.size() || p.uv_sets[size_t(tex_coord)].uv.empty())
          r.fail(what + ": samples TEXCOORD_" + std::to_string(tex_coord) + ", which mesh " + std::to_string(p.mesh) +
                 " primitive " + std::to_string(p.primitive) + " does not have");
        const auto& uv = p.uv_sets[size_t(tex_coord)].uv;
        constexpr float eps = 1e-4f;  // authoring tools write 1.00001 for 1
        for (uint32_t v : p.indices) {
          auto t = transform.apply(uv[2 * v], uv[2 * v + 1]);
          if ((repeats(wrap_s) && (t[0] < -eps || t[0] > 1 + eps)) || (repeats(wrap_t) && (t[1] < -eps || t[1] > 1 + eps))) {
            use.tiled = true;
            break;
          }
        }
        if (!img.uses.empty() && color_space_of(slot.role) != img.color_space) img.mixed_color_spaces = true;
        if (img.uses.empty()) img.color_space = color_space_of(slot.role);
        img.uses.push_back(use);
      }
    }
  }
  return asset;
}

std::vector<float> vertex_attribute(const GltfFile& file, int mesh, int primitive, const std::string& name, int width) {
  Reader r(file);
  const tinygltf::Model& m = r.model();
  if (mesh < 0 || size_t(mesh) >= m.meshes.size() || primitive < 0 ||
      size_t(primitive) >= m.meshes[size_t(mesh)].primitives.size())
    r.fail("mesh " + std::to_string(mesh) + " primitive " + std::to_string(primitive) + " does not exist");
  const auto& gp = m.meshes[size_t(mesh)].primitives[size_t(primitive)];
  const auto it = gp.attributes.find(name), pos = gp.attributes.find("POSITION");
  if (it == gp.attributes.end()) return {};
  const std::string what = "mesh " + std::to_string(mesh) + " primitive " + std::to_string(primitive) + " " + name;
  std::vector<float> v = r.floats(it->second, width, what);
  if (pos == gp.attributes.end() || pos->second < 0 || size_t(pos->second) >= m.accessors.size() ||
      v.size() != m.accessors[size_t(pos->second)].count * size_t(width))
    r.fail(what + ": count differs from POSITION count");
  for (float x : v)
    if (!std::isfinite(x)) r.fail(what + " has non-finite values");
  return v;
}

}  // namespace uvpress::io
