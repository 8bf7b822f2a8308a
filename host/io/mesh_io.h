// OBJ and OFF triangle meshes, with optional UVs (OBJ `vt`). Polygons are fan-split.
#pragma once

#include "core/mesh.h"

#include <string>

namespace uvpress::io {

// By extension (.obj, .off). Throws InputError naming the file, the line and the reason.
Mesh read_mesh(const std::string& path);
Mesh read_obj(const std::string& path);
Mesh read_off(const std::string& path);

// OBJ with `vt` when the mesh has UVs; written atomically.
void write_obj(const Mesh& mesh, const std::string& path);

}  // namespace uvpress::io
