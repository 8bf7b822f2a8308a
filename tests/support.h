// Test helpers: where the shared assets are, running the uvpress binary and the Khronos
// validator as a user would, scratch folders, and the CPU engine and the Vulkan one on lavapipe.
#pragma once

#include "core/image.h"
#include "engine.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace uvpress::test {

namespace fs = std::filesystem;

// ../shared beside the checkout, when present (tests that need it skip without it).
std::optional<fs::path> shared_dir();
// Every .gltf/.glb under shared/assets, sorted.
std::vector<fs::path> shared_assets();

// A fresh empty folder under the build tree, removed at the end of the test.
class Scratch {
 public:
  explicit Scratch(const std::string& name);
  ~Scratch();
  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& name) const { return path_ / name; }
  std::vector<std::string> files() const;  // every entry, hidden temporaries included

 private:
  fs::path path_;
};

struct RunResult {
  int exit_code = -1;
  std::string out, err;
  std::vector<std::string> err_lines() const;
};

// `p` as one shell word for run_uvpress (single-quoted; test paths hold no quote).
inline std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

// Runs the uvpress binary with `args` (shell words, already quoted as needed).
RunResult run_uvpress(const std::string& args);
// Runs a shell command (sh -c) with stdout and stderr captured.
RunResult run_shell(const std::string& command);

// Runs uvpress with `args` and checks the bad-input contract: exit 1, exactly one stderr
// line naming `file` and containing `reason`, nothing on stdout, `dir` unchanged (no
// output, no temporaries).
void check_input_error(const Scratch& dir, const std::string& args, const fs::path& file, const std::string& reason);

// A file's bytes (empty when it cannot be read), its JSON, and a text file of `lines`.
std::string read_file(const fs::path& p);
// Smooth colour with some detail, many more than 256 colours (as a re-baked texture has),
// in 8-bit values: 0.5 + 0.35 sin(x_freq x (c + 1) + y_freq y) + 0.1 cos(detail_freq (x + 2y)
// (3 - c mod 3)) in channel c; alpha (2 and 4 channels) opaque unless the alpha varies too.
// The image the codecs' tests write.
struct Waves {
  float x_freq = 0.05f, y_freq = 0.03f, detail_freq = 0.31f;
};
Image smooth_image(uint32_t w, uint32_t h, uint32_t channels, bool opaque_alpha = true, Waves waves = {});
nlohmann::json read_json(const fs::path& p);
void write_lines(const fs::path& p, const std::vector<std::string>& lines);

// The Khronos validator's summary of a .gltf/.glb: {"numErrors", "errors": {code: n}}.
nlohmann::json validate_gltf(const fs::path& file);

// The native CPU engine (default options), made once and shared: what tests re-bake on
// unless they compare engines.
engine::Engine& cpu_engine();

// Vulkan on lavapipe with the validation layer on; max_buffer_bytes 0 keeps the engine's
// default. Throws engine::EngineError when this machine has no lavapipe. UVPRESS_TEST_VULKAN=gpu
// takes the real GPU instead, so that the [vulkan] cases check a vendor's driver.
std::unique_ptr<engine::Engine> lavapipe(uint64_t max_buffer_bytes = 0);
bool vulkan_tests_on_gpu();

}  // namespace uvpress::test

// Catch2 v2 has no SKIP: say why and leave the test case.
#define UVPRESS_SKIP(why)              \
  do {                                 \
    WARN("skipped: " << (why));        \
    return;                            \
  } while (0)

// `var`: lavapipe(...) as above, or, where this machine has none, skip the test case saying why.
#define UVPRESS_LAVAPIPE_OR_SKIP(var, ...)                           \
  std::unique_ptr<::uvpress::engine::Engine> var;                    \
  try {                                                              \
    var = ::uvpress::test::lavapipe(__VA_ARGS__);                    \
  } catch (const ::uvpress::engine::EngineError& e) {                \
    UVPRESS_SKIP(std::string("no lavapipe: ") + e.what());           \
  }
