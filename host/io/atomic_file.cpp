#include "io/atomic_file.h"

#include "core/error.h"
#include "io/references.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <sys/stat.h>
#include <unistd.h>

namespace uvpress::io {

namespace fs = std::filesystem;

AtomicWriter::~AtomicWriter() {
  for (auto& e : entries_) std::remove(e.temp.c_str());
}

void AtomicWriter::add(const std::string& path, const void* bytes, size_t size) {
  fs::path target(path);
  fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  if (!fs::is_directory(dir)) throw InputError(path, "output folder '" + dir.string() + "' does not exist");
  std::string temp = (dir / ("." + target.filename().string() + ".tmp-XXXXXX")).string();
  int fd = mkstemp(temp.data());
  if (fd < 0) throw InputError(path, std::string("cannot create a file here: ") + std::strerror(errno));
  entries_.push_back({temp, path, uint64_t(size)});
  const char* p = static_cast<const char*>(bytes);
  while (size > 0) {
    ssize_t n = ::write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      int err = errno;
      ::close(fd);
      throw InputError(path, std::string("write failed: ") + std::strerror(err));
    }
    p += n, size -= size_t(n);
  }
  // Data on disk before the rename makes it visible, so a crash never leaves a torn file.
  if (::fsync(fd) != 0 || ::close(fd) != 0) throw InputError(path, std::string("write failed: ") + std::strerror(errno));
  ::chmod(temp.c_str(), 0644);
}

std::vector<std::pair<std::string, uint64_t>> AtomicWriter::staged() const {
  std::vector<std::pair<std::string, uint64_t>> out;
  for (const auto& e : entries_) out.emplace_back(e.target, e.size);
  return out;
}

void AtomicWriter::commit() {
  for (auto& e : entries_) {
    if (std::rename(e.temp.c_str(), e.target.c_str()) != 0)
      throw InputError(e.target, std::string("cannot rename into place: ") + std::strerror(errno));
    e.temp.clear();
  }
  entries_.clear();
}

namespace {

// Creates `dir` (and its parents) when missing and checks that a file can be created in
// it. `path` is what the error names.
void probe_folder(const fs::path& dir, const std::string& path) {
  std::error_code ec;
  if (!fs::exists(dir, ec)) fs::create_directories(dir, ec);
  if (!fs::is_directory(dir))
    throw InputError(path, "cannot create the output folder '" + dir.string() + "'" + (ec ? ": " + ec.message() : ""));
  std::string probe = (dir / ".uvpress-probe-XXXXXX").string();
  int fd = mkstemp(probe.data());
  if (fd < 0) throw InputError(path, "cannot write in the folder '" + dir.string() + "': " + std::strerror(errno));
  ::close(fd);
  std::remove(probe.c_str());
}

}  // namespace

void prepare_output_file(const std::string& path) {
  fs::path target(path);
  if (target.filename().empty()) throw InputError(path, "names a folder, not a file");
  std::error_code ec;
  if (fs::is_directory(target, ec)) throw InputError(path, "is a folder, not a file");
  probe_folder(target.parent_path().empty() ? fs::path(".") : target.parent_path(), path);
}

void prepare_output_folder(const std::string& dir) {
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) throw InputError(dir, "exists and is not a folder");
  probe_folder(fs::path(dir), dir);
}

std::vector<uint8_t> read_file(const std::string& path) {
  RegularFile file(path, path);
  if (file.size() > kMaxInputFileBytes)
    throw InputError(path, "is " + std::to_string(file.size()) + " bytes, more than the " +
                               std::to_string(kMaxInputFileBytes) + " uvpress reads for one file");
  return file.read_all();
}

std::string extension_of(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (auto& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace uvpress::io
