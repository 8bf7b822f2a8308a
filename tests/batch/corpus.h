// The bad-input corpus: malformed glTF assets generated from the demo asset, each with
// what uvpress must do with it (fail with a reason, or take a documented graceful path).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace uvpress::test {

struct CorpusCase {
  std::string name;
  std::filesystem::path file;  // the asset to give uvpress
  // Expected: exit 1 with one stderr line naming `file` and containing `reason`; or, when
  // `graceful`, exit 0 with a valid output (and `reason`, when set, in a warning line).
  std::string reason;
  bool graceful = false;
};

// Writes the corpus into `dir` (at least 30 cases). Deterministic. The reference cases
// (issue 13: "ref-*") are uploads in dir/uploads that reach for files outside that folder,
// FIFOs and oversized files; the files outside hold kOutsideMarker.
std::vector<CorpusCase> make_bad_input_corpus(const std::filesystem::path& dir);

// Bytes planted in every file outside dir/uploads that a reference case names
// (dir/secret.png: the demo texture with this text; dir/secret.bin): no output may ever
// contain them.
inline const std::string kOutsideMarker = "uvpress-outside-marker-0d15ea5e";

// `png` with `text` in a tEXt chunk: a copy byte for byte carries `text` along, a
// re-encoded image does not.
std::vector<uint8_t> png_with_text(std::vector<uint8_t> png, const std::string& text);

// A .glb of `json` (buffers[0] without a uri is the BIN chunk) and `bin`.
std::vector<uint8_t> make_glb(const std::string& json, const std::vector<uint8_t>& bin);

}  // namespace uvpress::test
