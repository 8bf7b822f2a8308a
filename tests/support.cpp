#include "support.h"

#include "core/error.h"
#include "io/atomic_file.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <sys/wait.h>

namespace uvpress::test {

std::optional<fs::path> shared_dir() {
  fs::path p = fs::path(UVPRESS_SOURCE_DIR).parent_path() / "shared";
  if (fs::is_directory(p / "assets")) return p;
  return std::nullopt;
}

std::vector<fs::path> shared_assets() {
  std::vector<fs::path> out;
  auto dir = shared_dir();
  if (!dir) return out;
  for (auto& e : fs::recursive_directory_iterator(*dir / "assets")) {
    auto ext = e.path().extension();
    if (ext == ".gltf" || ext == ".glb") out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

Scratch::Scratch(const std::string& name) {
  static std::mt19937 rng(std::random_device{}());
  path_ = fs::path(UVPRESS_BINARY_DIR) / "test-scratch" / (name + "-" + std::to_string(rng()));
  fs::remove_all(path_);
  fs::create_directories(path_);
}

Scratch::~Scratch() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

std::vector<std::string> Scratch::files() const {
  std::vector<std::string> out;
  for (auto& e : fs::directory_iterator(path_)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::string> RunResult::err_lines() const {
  std::vector<std::string> lines;
  std::istringstream in(err);
  for (std::string l; std::getline(in, l);)
    if (!l.empty()) lines.push_back(l);
  return lines;
}

Image smooth_image(uint32_t w, uint32_t h, uint32_t channels, bool opaque_alpha, Waves waves) {
  Image img;
  img.width = w, img.height = h, img.channels = channels;
  img.pixels.resize(size_t(w) * h * channels);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x)
      for (uint32_t c = 0; c < channels; ++c)
        img.at(x, y, c) = 0.5f + 0.35f * std::sin(waves.x_freq * float(x) * float(c + 1) + waves.y_freq * float(y)) +
                          0.1f * std::cos(waves.detail_freq * float(x + 2 * y) * float(3 - c % 3));
  if (opaque_alpha && (channels == 2 || channels == 4))
    for (uint32_t y = 0; y < h; ++y)
      for (uint32_t x = 0; x < w; ++x) img.at(x, y, channels - 1) = 1.0f;
  for (float& v : img.pixels) v = std::round(std::clamp(v, 0.0f, 1.0f) * 255.0f) / 255.0f;
  return img;
}

std::string read_file(const fs::path& p) {
  try {
    const std::vector<uint8_t> bytes = io::read_file(p.string());
    return std::string(bytes.begin(), bytes.end());
  } catch (const InputError&) {
    return {};  // absent or unreadable (a log Chromium never wrote)
  }
}

nlohmann::json read_json(const fs::path& p) { return nlohmann::json::parse(read_file(p)); }

void write_lines(const fs::path& p, const std::vector<std::string>& lines) {
  std::ofstream out(p);
  for (const auto& l : lines) out << l << "\n";
}

RunResult run_shell(const std::string& command) {
  Scratch io("run");
  std::string full = command + " >" + (io / "out").string() + " 2>" + (io / "err").string() + " </dev/null";
  int status = std::system(full.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = read_file(io / "out");
  r.err = read_file(io / "err");
  return r;
}

RunResult run_uvpress(const std::string& args) { return run_shell(std::string(UVPRESS_BINARY) + " " + args); }

void check_input_error(const Scratch& dir, const std::string& args, const fs::path& file, const std::string& reason) {
  auto before = dir.files();
  auto r = run_uvpress(args);
  INFO("uvpress " << args << "\nstderr: " << r.err);
  CHECK(r.exit_code == 1);
  auto lines = r.err_lines();
  REQUIRE(lines.size() == 1);
  CHECK_THAT(lines[0], Catch::Contains(file.string()));
  CHECK_THAT(lines[0], Catch::Contains(reason));
  CHECK(r.out.empty());
  CHECK(dir.files() == before);
}

nlohmann::json validate_gltf(const fs::path& file) {
  fs::path script = fs::path(UVPRESS_SOURCE_DIR) / "tools" / "validate-gltf.mjs";
  RunResult r = run_shell("node " + script.string() + " '" + file.string() + "'");
  if (r.exit_code != 0)
    throw std::runtime_error("validator did not run on " + file.string() + " (run tools/install-deps.sh): " + r.err);
  return nlohmann::json::parse(r.out);
}

engine::Engine& cpu_engine() {
  static const std::unique_ptr<engine::Engine> cpu = engine::make_cpu_engine({});
  return *cpu;
}

std::unique_ptr<engine::Engine> lavapipe(uint64_t max_buffer_bytes) {
  engine::EngineOptions o;
  o.validation = true;
  o.max_buffer_bytes = max_buffer_bytes;
  // UVPRESS_TEST_VULKAN=gpu runs the same [vulkan] cases on a real GPU (a lent device machine);
  // CI never sets it.
  return engine::make_vulkan_engine(vulkan_tests_on_gpu() ? engine::DeviceRequest::Gpu : engine::DeviceRequest::Lavapipe, o);
}

bool vulkan_tests_on_gpu() {
  const char* kind = std::getenv("UVPRESS_TEST_VULKAN");
  return kind && std::string(kind) == "gpu";
}

}  // namespace uvpress::test
