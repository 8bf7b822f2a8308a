// What an asset weighs on disk and on the wire: the .gltf JSON with every external buffer
// and image it names, or the .glb (whose BIN chunk holds them). The summary lines and
// reports count this, not the .gltf text alone (Fox.gltf is 44 KB of a 187 KB asset).
#pragma once

#include "io/atomic_file.h"
#include "io/references.h"

#include <cstdint>
#include <string>

namespace uvpress::io {

struct AssetBytes {
  uint64_t file = 0;     // the .gltf or .glb itself
  uint64_t buffers = 0;  // external buffer files
  uint64_t images = 0;   // external image files
  uint64_t ktx2 = 0;     // GPU-ready KTX2 copies beside it (io/gpu_textures.h): an alternative to
                         // the images for engines that load KTX2, not part of total()
  uint64_t total() const { return file + buffers + images; }
};

// Files are found by the loader's rule (references.h); a file named twice counts once.
// Throws InputError as the loader would for a reference that is refused or missing (a KTX2
// copy that is missing or refused counts 0: the asset is whole without it).
AssetBytes asset_bytes(const std::string& path, const RefPolicy& refs = {});
// The same for an asset staged in `writer` (save_gltf's staged form) and not yet committed:
// `path` itself, `.bin` buffers, `.ktx2` copies and the rest images.
AssetBytes staged_asset_bytes(const AtomicWriter& writer, const std::string& path);

}  // namespace uvpress::io
