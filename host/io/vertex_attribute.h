// One float vertex attribute of a glTF primitive beyond what io::Asset keeps (POSITION and
// TEXCOORD_n): NORMAL and TANGENT for eval's lit shading. Decoded by the same bounds-checked
// reader as build_asset (host/io/asset.cpp): normalized integers and sparse accessors.
#pragma once

#include "io/gltf_io.h"

#include <string>
#include <vector>

namespace uvpress::io {

// `name` (e.g. "NORMAL", width 3; "TANGENT", width 4) of primitive `primitive` of mesh
// `mesh`, `width` floats per vertex; empty when the primitive has no such attribute.
// Throws InputError(file.path, reason) for an accessor of the wrong type, a count other
// than POSITION's, non-finite values, or bytes out of range.
std::vector<float> vertex_attribute(const GltfFile& file, int mesh, int primitive, const std::string& name, int width);

}  // namespace uvpress::io
