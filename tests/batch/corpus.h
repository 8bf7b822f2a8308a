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

// Writes the corpus into `dir` (at least 30 cases). Deterministic.
std::vector<CorpusCase> make_bad_input_corpus(const std::filesystem::path& dir);

}  // namespace uvpress::test
