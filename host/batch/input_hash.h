// batch's input and output hashes: what resume compares to tell a current result from a
// stale one.
#pragma once

#include "io/references.h"

#include <string>

namespace uvpress::batch {

// FNV-1a 64 (hex) over a file and every file its buffers and images name (.gltf or .glb),
// and the KTX2 copies it names, read only as `refs` allows (io/references.h: no FIFO, device
// or oversized file is read; a refused reference adds its error line instead). "" when the
// file cannot be read.
std::string hash_asset(const std::string& path, const io::RefPolicy& refs = {});

}  // namespace uvpress::batch
