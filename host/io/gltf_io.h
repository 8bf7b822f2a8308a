// glTF 2.0 in and out through tinygltf: .gltf with external or data: resources, and .glb.
// Everything uvpress does not change survives a load/save round trip: the tinygltf model
// is kept whole, images stay in their encoded form (no re-encoding of untouched textures).
#pragma once

#include "io/atomic_file.h"
#include "io/references.h"

#include <tiny_gltf.h>

#include <cstdint>
#include <string>
#include <vector>

namespace uvpress::io {

// A GPU-ready copy of one image: a KTX2 file (io/gpu_textures.h) that lives beside the glTF
// and is named in the image's extras, {"uvpress_ktx2": {"uri": ..., "source": "fnv1a64:..."}}.
// `source` is image_fingerprint of the image bytes it was made from: when the image is
// re-baked, the copy no longer matches it and save_gltf drops it.
struct Ktx2Sidecar {
  std::vector<uint8_t> bytes;  // empty: none
  uint64_t source = 0;
};

struct GltfFile {
  std::string path;
  tinygltf::Model model;
  // The encoded bytes (PNG, JPEG, ...) of every image, wherever the file kept them. A stage
  // that re-bakes a texture replaces its entry; save writes what is here.
  std::vector<std::vector<uint8_t>> image_bytes;
  // Per image (or empty): its KTX2 copy, read from beside the input (checked as image files
  // are, and by io/ktx2.h; one that is missing, unreadable or made from other image bytes is
  // dropped) or made by attach_astc_textures (io/gpu_textures.h).
  std::vector<Ktx2Sidecar> image_ktx2;
};

// FNV-1a, 64 bit, of an image's encoded bytes: what a KTX2 copy was made from.
uint64_t image_fingerprint(const std::vector<uint8_t>& bytes);

// Extensions uvpress reads correctly when an asset lists them as required.
bool is_supported_required_extension(const std::string& name);

// Throws InputError(path, reason) for anything unreadable: a missing file, bad JSON or
// binary layout, broken resources, a missing image, an unsupported required extension.
// External files are read only as `refs` allows (references.h), and every image, kept byte
// for byte, must pass check_image (a header that decodes, its mimeType, its size).
GltfFile load_gltf(const std::string& path, const RefPolicy& refs = {});

// How save_gltf names the files beside a .gltf.
struct SaveOptions {
  // Each image keeps its own file name (Texture.png) where no other file of this output
  // takes it and the folder holds no file of that name with other bytes (the input's own
  // image when writing beside it, another asset's); else, and by default, <stem>_<name>,
  // which never collides across assets written to one folder (batch relies on it).
  bool keep_image_names = false;
};

// Writes by extension: .glb (one binary chunk holding every buffer and image) or .gltf
// (pretty JSON plus <stem>.bin and one file per image beside it, named as `options` says).
// Either way, each image's KTX2 copy that still matches its bytes is written beside the
// output as <stem>_<image>.ktx2 and named in the image's extras (see Ktx2Sidecar). All
// files are written to temporaries and renamed at the end: no partial output. Throws
// InputError.
void save_gltf(const GltfFile& file, const std::string& path, const SaveOptions& options = {});
// The same, staged in `writer` and not committed: the caller adds what must appear with the
// asset (its report) and commits them together, so that a failed report leaves no asset.
void save_gltf(const GltfFile& file, const std::string& path, const SaveOptions& options, AtomicWriter& writer);

// True for the output extensions save_gltf takes.
bool is_gltf_output_path(const std::string& path);

}  // namespace uvpress::io
