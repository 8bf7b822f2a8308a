// What an asset can make uvpress read. Assets come from uploads: a buffer or image URI is
// untrusted text that names a file, and must not pull in a file from elsewhere on the worker
// (keys, other customers' assets), hang the reader (a FIFO, /dev/zero) or exhaust memory (a
// huge or sparse file). One rule, applied by every reader — the glTF loader (tinygltf's file
// callbacks serve only what passed it) and batch's input hashing:
//   percent-decode the URI, resolve it against the asset's folder, normalize and resolve
//   symlinks; refuse it unless it stays inside that folder (unless the policy allows it),
//   unless it is a regular file, and unless its size is within the limits — all before a
//   byte is read.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace uvpress::io {

// Per-file read limits: a buffer's file must be exactly its declared byteLength and at most
// this; an image file at most kMaxImageFileBytes (a 16K x 16K texture compresses far below).
constexpr uint64_t kMaxBufferBytes = uint64_t(2) << 30;
constexpr uint64_t kMaxImageFileBytes = uint64_t(512) << 20;

struct RefPolicy {
  // --allow-outside-refs: a reference may leave the asset's folder (trusted layouts that
  // share textures between folders). The other checks still apply.
  bool allow_outside = false;
};

// One buffer or image URI that names a file (data: URIs are not references).
struct ExternalRef {
  std::string what;          // "buffer 0", "image 2": names the reference in errors
  std::string uri;           // as written in the asset, still percent-encoded
  bool buffer = false;       // a buffer (else an image)
  int64_t byte_length = -1;  // a buffer's declared byteLength; -1 when absent or not a number
};

// The references in a .gltf's JSON or a .glb's JSON chunk, buffers first. Empty when the
// bytes do not parse: the loader says why.
std::vector<ExternalRef> external_refs(const std::vector<uint8_t>& asset_bytes);

// The KTX2 copies its images name in extras.uvpress_ktx2 (io/gltf_io.h, `--texture-format
// astc`), as "image N KTX2" references: optional files (the asset is whole without them)
// that are read, hashed and counted by the same rule. Empty when the bytes do not parse.
std::vector<ExternalRef> ktx2_sidecar_refs(const std::vector<uint8_t>& asset_bytes);

// A regular file opened for reading, its size known before anything is read: callers check
// size() against their limit first. Opening never blocks: FIFOs, devices, sockets and
// folders are refused before they are opened (and again on what was opened).
class RegularFile {
 public:
  // Throws InputError(label, reason): "not found", "is a FIFO, not a regular file", ...
  RegularFile(const std::filesystem::path& path, const std::string& label);
  ~RegularFile();
  RegularFile(RegularFile&& other) noexcept;
  RegularFile(const RegularFile&) = delete;
  RegularFile& operator=(const RegularFile&) = delete;
  RegularFile& operator=(RegularFile&&) = delete;

  uint64_t size() const { return size_; }
  // Exactly size() bytes; InputError when the file changed size under us.
  std::vector<uint8_t> read_all();
  // The same bytes in chunks (hashing without holding a whole buffer).
  void read_chunks(const std::function<void(const uint8_t*, size_t)>& sink);

 private:
  int fd_ = -1;
  uint64_t size_ = 0;
  std::string label_;
};

// "%2e%2E/x" -> "../x". Throws std::invalid_argument for a malformed escape or a NUL byte.
// '+' stays '+' (RFC 3986; tinygltf would look for a space instead: such a file is then
// not among the checked ones and is refused, never read unchecked).
std::string percent_decode(const std::string& uri);

// A URI as one error line can show it: control characters replaced, at most 80 characters.
std::string shown_uri(const std::string& uri);

// A checked, open reference: `path` is where it resolved (canonical), `file` is open and
// within the size limits, nothing read yet.
struct OpenRef {
  std::filesystem::path path;
  RegularFile file;
};

// Applies the rule to `ref` of the asset at `asset_path`. Throws InputError(asset_path,
// "<what>: '<uri>' <reason>"), e.g. "image 0: '../../etc/hostname' points outside the
// asset's folder".
OpenRef open_ref(const std::string& asset_path, const ExternalRef& ref, const RefPolicy& policy);

}  // namespace uvpress::io
