#include "batch/input_hash.h"

#include "core/error.h"
#include "io/atomic_file.h"

#include <cstdint>
#include <cstdio>
#include <vector>

namespace uvpress::batch {

namespace {

uint64_t fnv1a(uint64_t h, const void* data, size_t n) {
  const auto* p = static_cast<const uint8_t*>(data);
  for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
  return h;
}

std::string to_hex(uint64_t h) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", (unsigned long long)h);
  return buf;
}

}  // namespace

std::string hash_asset(const std::string& path, const io::RefPolicy& refs) {
  std::vector<uint8_t> bytes;
  try {
    bytes = io::read_file(path);
  } catch (const InputError&) {
    return "";
  }
  uint64_t h = fnv1a(0xcbf29ce484222325ull, bytes.data(), bytes.size());
  std::vector<io::ExternalRef> refs_and_copies = io::external_refs(bytes);
  for (auto& ref : io::ktx2_sidecar_refs(bytes)) refs_and_copies.push_back(std::move(ref));
  for (const auto& ref : refs_and_copies) {
    h = fnv1a(h, ref.uri.data(), ref.uri.size() + 1);
    try {
      io::OpenRef open = io::open_ref(path, ref, refs);  // the loader's rule: no hang, no huge read
      open.file.read_chunks([&](const uint8_t* p, size_t n) { h = fnv1a(h, p, n); });
    } catch (const InputError& e) {
      // The load fails with this same line (or drops the KTX2 copy); hashing it makes a
      // fixed reference a new input, and a removed copy a stale output.
      const std::string why = e.what();
      h = fnv1a(h, why.data(), why.size() + 1);
    }
  }
  return to_hex(h);
}

}  // namespace uvpress::batch
