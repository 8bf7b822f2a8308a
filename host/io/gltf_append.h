// Adding new data to a loaded glTF: stages that write new UVs or geometry append to
// buffer 0 instead of editing accessors other primitives may share.
#pragma once

#include <tiny_gltf.h>

#include <cstdint>
#include <vector>

namespace uvpress::io {

// A new bufferView over `bytes` appended to buffer 0 at a 4-byte aligned offset.
int append_buffer_view(tinygltf::Model& model, const void* data, size_t bytes, int target);

// A new float accessor (TINYGLTF_TYPE_VEC2 / VEC3 / ...) over `values`, with min and max
// (which the validator requires for positions and which readers use for bounds).
int append_float_accessor(tinygltf::Model& model, const std::vector<float>& values, int type,
                          int target = TINYGLTF_TARGET_ARRAY_BUFFER);

// A new unsigned-short index accessor.
int append_index_accessor(tinygltf::Model& model, const std::vector<uint16_t>& indices);

}  // namespace uvpress::io
