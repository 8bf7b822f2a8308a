// OBJ and OFF triangle meshes, with optional UVs (OBJ `vt`). Polygons are fan-split.
#pragma once

#include "core/mesh.h"
#include "io/atomic_file.h"

#include <string>
#include <utility>
#include <vector>

namespace uvpress::io {

// What an OBJ carries besides geometry and UVs, so that a rewrite (flatten's new `vt`)
// keeps it: material libraries and assignments, and per-corner normals. Object and group
// names and smoothing groups are not kept (`dropped` counts their lines).
struct ObjExtras {
  std::vector<std::string> mtllib;      // each `mtllib` line's argument, in order
  std::vector<std::pair<size_t, std::string>> usemtl;  // (first triangle, material), by triangle
  std::vector<double> normals;          // x y z per `vn`
  std::vector<uint32_t> normal_triangles;  // 3 `vn` indices per triangle; empty unless every face has them
  size_t dropped = 0;                   // `o`, `g`, `s` lines
};

// By extension (.obj, .off). Throws InputError naming the file, the line and the reason.
Mesh read_mesh(const std::string& path, ObjExtras* extras = nullptr);
Mesh read_obj(const std::string& path, ObjExtras* extras = nullptr);
Mesh read_off(const std::string& path);

// OBJ with `vt` when the mesh has UVs, and what `extras` holds (mtllib, usemtl, vn for the
// same triangles); written atomically.
void write_obj(const Mesh& mesh, const std::string& path, const ObjExtras* extras = nullptr);
// The same, staged in `writer` (committed by the caller with what must appear with it).
void write_obj(const Mesh& mesh, const std::string& path, const ObjExtras* extras, AtomicWriter& writer);

}  // namespace uvpress::io
