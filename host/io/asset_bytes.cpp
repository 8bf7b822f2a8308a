#include "io/asset_bytes.h"

#include "core/error.h"
#include "io/atomic_file.h"

#include <set>

namespace uvpress::io {

AssetBytes asset_bytes(const std::string& path, const RefPolicy& refs) {
  const std::vector<uint8_t> bytes = read_file(path);
  AssetBytes out;
  out.file = bytes.size();
  std::set<std::string> seen;
  for (const ExternalRef& ref : external_refs(bytes)) {
    OpenRef open = open_ref(path, ref, refs);
    if (!seen.insert(open.path.string()).second) continue;
    (ref.buffer ? out.buffers : out.images) += open.file.size();
  }
  for (const ExternalRef& ref : ktx2_sidecar_refs(bytes)) {
    try {
      OpenRef open = open_ref(path, ref, refs);
      if (seen.insert(open.path.string()).second) out.ktx2 += open.file.size();
    } catch (const InputError&) {
    }
  }
  return out;
}

AssetBytes staged_asset_bytes(const AtomicWriter& writer, const std::string& path) {
  AssetBytes out;
  for (const auto& [target, size] : writer.staged()) {
    const std::string ext = extension_of(target);
    if (target == path) out.file += size;
    else if (ext == ".bin") out.buffers += size;
    else if (ext == ".ktx2") out.ktx2 += size;
    else out.images += size;
  }
  return out;
}

}  // namespace uvpress::io
