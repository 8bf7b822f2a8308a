// Outputs appear whole or not at all: every file is written to a temporary name beside
// its target and renamed into place only when all of them have been written.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace uvpress::io {

class AtomicWriter {
 public:
  AtomicWriter() = default;
  ~AtomicWriter();  // removes the temporaries of an uncommitted write
  AtomicWriter(const AtomicWriter&) = delete;
  AtomicWriter& operator=(const AtomicWriter&) = delete;

  // Writes `bytes` to a temporary beside `path`. Throws InputError(path, reason).
  void add(const std::string& path, const void* bytes, size_t size);
  void add(const std::string& path, const std::vector<uint8_t>& bytes) { add(path, bytes.data(), bytes.size()); }
  void add(const std::string& path, const std::string& text) { add(path, text.data(), text.size()); }
  // Renames every temporary onto its target, in the order added (add the main file last).
  void commit();

  // The files added and not yet committed: target path and size in bytes, in order (so
  // that a report written with the asset can say what the asset will cost).
  std::vector<std::pair<std::string, uint64_t>> staged() const;

 private:
  struct Entry {
    std::string temp, target;
    uint64_t size = 0;
  };
  std::vector<Entry> entries_;
};

// The one rule for outputs, applied by every command before any work: the folder an output
// file goes in is created when missing, and a file must be creatable there (a temporary is
// created and removed). Throws InputError(path, reason).
void prepare_output_file(const std::string& path);
// The same for an output folder: created when missing, then probed.
void prepare_output_folder(const std::string& dir);

// The most read_file reads (tinygltf takes sizes as 32 bits; a .glb cannot be larger).
constexpr uint64_t kMaxInputFileBytes = 0xffffffffu;

// Reads a whole regular file of at most kMaxInputFileBytes. Throws InputError(path,
// "not found" / reason); a FIFO or device is refused, never opened.
std::vector<uint8_t> read_file(const std::string& path);

// Lower-case extension with the dot (".glb"), or "" when there is none.
std::string extension_of(const std::string& path);

}  // namespace uvpress::io
