#include "io/gltf_append.h"

#include <algorithm>
#include <limits>

namespace uvpress::io {

int append_buffer_view(tinygltf::Model& m, const void* data, size_t bytes, int target) {
  if (m.buffers.empty()) m.buffers.emplace_back();
  auto& buffer = m.buffers[0].data;
  buffer.resize((buffer.size() + 3) / 4 * 4, 0);
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = buffer.size();
  view.byteLength = bytes;
  view.target = target;
  const auto* p = static_cast<const uint8_t*>(data);
  buffer.insert(buffer.end(), p, p + bytes);
  m.bufferViews.push_back(view);
  return int(m.bufferViews.size() - 1);
}

int append_float_accessor(tinygltf::Model& m, const std::vector<float>& values, int type, int target) {
  const size_t width = size_t(tinygltf::GetNumComponentsInType(uint32_t(type)));
  tinygltf::Accessor a;
  a.bufferView = append_buffer_view(m, values.data(), values.size() * sizeof(float), target);
  a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
  a.type = type;
  a.count = values.size() / width;
  a.minValues.assign(width, values.empty() ? 0.0 : std::numeric_limits<double>::infinity());
  a.maxValues.assign(width, values.empty() ? 0.0 : -std::numeric_limits<double>::infinity());
  for (size_t i = 0; i < values.size(); ++i) {
    a.minValues[i % width] = std::min(a.minValues[i % width], double(values[i]));
    a.maxValues[i % width] = std::max(a.maxValues[i % width], double(values[i]));
  }
  m.accessors.push_back(a);
  return int(m.accessors.size() - 1);
}

int append_index_accessor(tinygltf::Model& m, const std::vector<uint16_t>& indices) {
  tinygltf::Accessor a;
  a.bufferView = append_buffer_view(m, indices.data(), indices.size() * sizeof(uint16_t),
                                    TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
  a.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
  a.type = TINYGLTF_TYPE_SCALAR;
  a.count = indices.size();
  m.accessors.push_back(a);
  return int(m.accessors.size() - 1);
}

}  // namespace uvpress::io
