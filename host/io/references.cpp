#include "io/references.h"

#include "core/error.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <stdexcept>
#include <sys/stat.h>
#include <unistd.h>

namespace uvpress::io {

namespace fs = std::filesystem;

namespace {

// The JSON text of a .glb (its first chunk) or of a .gltf (the whole file).
std::string json_text(const std::vector<uint8_t>& b) {
  const bool glb = b.size() >= 4 && std::memcmp(b.data(), "glTF", 4) == 0;
  if (!glb) return std::string(b.begin(), b.end());
  if (b.size() < 20 || std::memcmp(&b[16], "JSON", 4) != 0) return "";
  uint32_t length;
  std::memcpy(&length, &b[12], 4);  // little-endian host
  if (length > b.size() - 20) return "";
  return std::string(b.begin() + 20, b.begin() + 20 + long(length));
}

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a plain file";
}

// Only regular files: a FIFO blocks the reader forever, a device never ends (/dev/zero).
void require_regular(const struct stat& st, const std::string& label) {
  if (!S_ISREG(st.st_mode)) throw InputError(label, std::string("is ") + kind_of(st.st_mode) + ", not a regular file");
}

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool starts_with(const fs::path& path, const fs::path& folder) {
  auto p = path.begin();
  for (auto f = folder.begin(); f != folder.end(); ++f, ++p)
    if (p == path.end() || *p != *f) return false;
  return true;
}

std::string bytes_text(uint64_t n) { return std::to_string(n) + " bytes"; }

}  // namespace

std::vector<ExternalRef> external_refs(const std::vector<uint8_t>& asset_bytes) {
  std::vector<ExternalRef> refs;
  const nlohmann::json j = nlohmann::json::parse(json_text(asset_bytes), nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) return refs;
  for (const char* key : {"buffers", "images"}) {
    const bool buffer = std::strcmp(key, "buffers") == 0;
    auto list = j.find(key);
    if (list == j.end() || !list->is_array()) continue;
    for (size_t i = 0; i < list->size(); ++i) {
      const auto& e = (*list)[i];
      if (!e.is_object() || !e.contains("uri") || !e["uri"].is_string()) continue;
      std::string uri = e["uri"].get<std::string>();
      if (uri.rfind("data:", 0) == 0) continue;  // embedded, decoded by tinygltf
      ExternalRef ref{(buffer ? "buffer " : "image ") + std::to_string(i), uri, buffer, -1};
      if (buffer && e.contains("byteLength") && e["byteLength"].is_number()) {
        const double n = e["byteLength"].get<double>();
        ref.byte_length = n >= 0 && n < 9e18 ? int64_t(n) : INT64_MAX;
      }
      refs.push_back(std::move(ref));
    }
  }
  return refs;
}

std::vector<ExternalRef> ktx2_sidecar_refs(const std::vector<uint8_t>& asset_bytes) {
  std::vector<ExternalRef> refs;
  const nlohmann::json j = nlohmann::json::parse(json_text(asset_bytes), nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) return refs;
  auto images = j.find("images");
  if (images == j.end() || !images->is_array()) return refs;
  for (size_t i = 0; i < images->size(); ++i) {
    const auto& e = (*images)[i];
    if (!e.is_object() || !e.contains("extras") || !e["extras"].is_object()) continue;
    const auto& extras = e["extras"];
    auto k = extras.find("uvpress_ktx2");
    if (k == extras.end() || !k->is_object() || !k->contains("uri") || !(*k)["uri"].is_string()) continue;
    refs.push_back({"image " + std::to_string(i) + " KTX2", (*k)["uri"].get<std::string>(), false, -1});
  }
  return refs;
}

RegularFile::RegularFile(const fs::path& path, const std::string& label) : label_(label) {
  struct stat st;
  // stat before open: opening a FIFO blocks until a writer comes, opening a device can act.
  if (::stat(path.c_str(), &st) != 0)
    throw InputError(label, errno == ENOENT || errno == ENOTDIR ? "not found" : std::string("cannot be read (") + std::strerror(errno) + ")");
  require_regular(st, label);
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd_ < 0) throw InputError(label, std::string("cannot be opened (") + std::strerror(errno) + ")");
  // Again on what was opened: the path may name something else by now.
  if (::fstat(fd_, &st) != 0) st.st_mode = 0;
  if (!S_ISREG(st.st_mode)) {
    ::close(fd_);
    fd_ = -1;
    require_regular(st, label);
  }
  size_ = uint64_t(st.st_size);
}

RegularFile::~RegularFile() {
  if (fd_ >= 0) ::close(fd_);
}

RegularFile::RegularFile(RegularFile&& o) noexcept : fd_(o.fd_), size_(o.size_), label_(std::move(o.label_)) { o.fd_ = -1; }

void RegularFile::read_chunks(const std::function<void(const uint8_t*, size_t)>& sink) {
  std::vector<uint8_t> buf(size_t(std::min<uint64_t>(size_, 1 << 20)));
  // Never past size(): the limit the caller checked is the most that is read.
  for (uint64_t at = 0; at < size_;) {
    const size_t want = size_t(std::min<uint64_t>(buf.size(), size_ - at));
    const ssize_t n = ::pread(fd_, buf.data(), want, off_t(at));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw InputError(label_, std::string("read failed (") + std::strerror(errno) + ")");
    if (n == 0) throw InputError(label_, "changed while it was read (shorter than when opened)");
    sink(buf.data(), size_t(n));
    at += uint64_t(n);
  }
}

std::vector<uint8_t> RegularFile::read_all() {
  std::vector<uint8_t> bytes;
  bytes.reserve(size_t(size_));
  read_chunks([&](const uint8_t* p, size_t n) { bytes.insert(bytes.end(), p, p + n); });
  return bytes;
}

std::string shown_uri(const std::string& uri) {
  std::string s = uri.size() > 80 ? uri.substr(0, 77) + "..." : uri;
  for (auto& c : s)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  return s;
}

std::string percent_decode(const std::string& uri) {
  std::string out;
  out.reserve(uri.size());
  for (size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] != '%') {
      out += uri[i];
      continue;
    }
    const int hi = i + 2 < uri.size() ? hex_digit(uri[i + 1]) : -1, lo = hi >= 0 ? hex_digit(uri[i + 2]) : -1;
    if (lo < 0) throw std::invalid_argument("malformed percent-escape");
    out += char(hi * 16 + lo);
    i += 2;
  }
  if (out.find('\0') != std::string::npos) throw std::invalid_argument("a NUL byte");
  return out;
}

OpenRef open_ref(const std::string& asset_path, const ExternalRef& ref, const RefPolicy& policy) {
  const std::string name = ref.what + ": '" + shown_uri(ref.uri) + "'";
  auto fail = [&](const std::string& reason) { return InputError(asset_path, name + " " + reason); };
  std::string decoded;
  try {
    decoded = percent_decode(ref.uri);  // what tinygltf will look for, so what is checked
  } catch (const std::invalid_argument& e) {
    throw fail(std::string("is not a valid URI (") + e.what() + ")");
  }
  std::error_code ec;
  const fs::path parent = fs::path(asset_path).parent_path();
  const fs::path folder = fs::canonical(parent.empty() ? fs::path(".") : parent, ec);
  if (ec) throw InputError(asset_path, "cannot resolve the asset's folder (" + ec.message() + ")");
  // Normalized with every existing symlink resolved: "a/../../x", an absolute path and a
  // link inside the folder that points out all end up outside here.
  const fs::path target = fs::weakly_canonical(folder / fs::path(decoded), ec);
  if (ec) throw fail("cannot be resolved (" + ec.message() + ")");
  if (!policy.allow_outside && !starts_with(target, folder)) throw fail("points outside the asset's folder");
  if (ref.buffer && ref.byte_length > int64_t(kMaxBufferBytes))
    throw fail("declares byteLength " + std::to_string(ref.byte_length) + ", more than the " +
               bytes_text(kMaxBufferBytes) + " uvpress reads for one buffer");
  RegularFile file = [&] {
    try {
      return RegularFile(target, asset_path);
    } catch (const InputError& e) {
      const std::string why = e.what();
      // A missing file: say where it was looked for.
      throw fail(why == "not found" ? "not found (looked for " + target.string() + ")" : why);
    }
  }();
  // Sizes before reading: a file much larger than declared is never read whole.
  const uint64_t size = file.size();
  if (ref.buffer && ref.byte_length >= 0 && size != uint64_t(ref.byte_length))
    throw fail("is " + bytes_text(size) + ", but the buffer declares byteLength " + std::to_string(ref.byte_length));
  const uint64_t cap = ref.buffer ? kMaxBufferBytes : kMaxImageFileBytes;
  if (size > cap)
    throw fail("is " + bytes_text(size) + ", more than the " + bytes_text(cap) + " uvpress reads for one " +
               (ref.buffer ? "buffer" : "image"));
  return OpenRef{target, std::move(file)};
}

}  // namespace uvpress::io
