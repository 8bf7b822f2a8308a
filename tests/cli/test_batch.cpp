// uvpress batch: per-asset reports and summary, resume, shards, --collect, --jobs, a batch
// killed with SIGKILL mid-way then resumed, --texture-format astc and --strict.
#include <catch2/catch.hpp>

#include "batch/input_hash.h"
#include "core/report_schema.h"
#include "io/atomic_file.h"
#include "io/gltf_io.h"
#include "io/references.h"
#include "pipeline/demo_asset.h"
#include "pipeline/reparam.h"
#include "support.h"

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <spawn.h>
#include <sys/wait.h>
#include <thread>

extern char** environ;

using namespace uvpress;
using test::run_uvpress;
using json = nlohmann::json;

namespace {

using test::quoted;
using test::read_json;

// `count` demo assets (different sizes, so different bytes) and a manifest listing them.
std::vector<test::fs::path> write_assets(const test::fs::path& dir, int count, int grid = 6, int texture = 32) {
  std::vector<test::fs::path> out;
  test::fs::create_directories(dir / "in");
  for (int k = 0; k < count; ++k) {
    auto p = dir / "in" / ("asset" + std::to_string(k) + ".glb");
    io::save_gltf(pipeline::make_demo_asset({grid + k, texture}), p.string());
    out.push_back(p);
  }
  return out;
}

// Exit code of uvpress run with extra environment variables (shell words).
int run_uvpress_env(const std::string& env, const std::string& args) {
  int status = std::system((env + " " + UVPRESS_BINARY + " " + args + " >/dev/null 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

}  // namespace

TEST_CASE("batch: reports, summary, one failure never stops the others, resume", "[batch][cli]") {
  test::Scratch dir("batch-cli");
  auto assets = write_assets(dir.path(), 3);
  std::ofstream(dir / "in" / "broken.glb") << "glTF this is not";
  test::write_lines(dir / "list.txt", {"in/asset0.glb", "in/broken.glb", "in/asset1.glb", "in/asset2.glb"});
  auto out = dir / "out";
  const std::string cmd = "batch --manifest " + quoted(dir / "list.txt") + " -o " + quoted(out) + " --no-optimize --device cpu";

  auto r = run_uvpress(cmd + " --report " + quoted(dir / "run.json"));
  INFO(r.out << r.err);
  CHECK(r.exit_code == 1);
  CHECK_THAT(r.out, Catch::Contains("asset0") && Catch::Contains("broken") && Catch::Contains("FAILED"));
  CHECK_THAT(r.out, Catch::Contains("4 assets: 3 ok, 0 skipped, 1 failed"));
  CHECK_THAT(r.out, Catch::Contains("written") && Catch::Contains("q / q resize") && Catch::Contains("size in -> out"));
  // Each ok row shows the whole asset's bytes before and after.
  CHECK_THAT(r.out, Catch::Matches("(.|\n)*asset0 +ok .* [0-9.]+ K?B -> [0-9.]+ K?B (.|\n)*"));
  CHECK_THAT(r.err, Catch::Contains("batch [4/4]"));
  auto summary = read_json(out / "summary.json");
  CHECK(summary == read_json(dir / "run.json"));
  CHECK(summary["counts"]["ok"] == 3);
  CHECK(summary["schema"] == kReportSchema);
  CHECK(summary["counts"]["failed"] == 1);
  auto broken = read_json(out / "broken.report.json");
  CHECK(broken["status"] == "failed");
  CHECK_THAT(broken["error"].get<std::string>(), Catch::Contains("broken.glb"));
  CHECK_FALSE(test::fs::exists(out / "broken.glb"));
  for (int k = 0; k < 3; ++k) {
    std::string name = "asset" + std::to_string(k);
    auto rep = read_json(out / (name + ".report.json"));
    CHECK(rep["status"] == "ok");
    CHECK(rep["schema"] == kReportSchema);
    CHECK(rep["input_hash"] == batch::hash_asset(assets[size_t(k)].string()));
    CHECK(rep["output_hash"] == batch::hash_asset((out / (name + ".glb")).string()));
    CHECK(rep["reparam"]["cost_ratio"].get<double>() > 0);
    // The summary row and the table say what was written and the two q the guard compared.
    const auto& row = summary["assets"][k == 0 ? 0 : k + 1];
    REQUIRE(row["name"] == name);
    CHECK(row["written"] == rep["reparam"]["chosen"]);
    REQUIRE(rep["reparam"]["guard"].contains("q_resize"));
    CHECK(row["q_resize"] == rep["reparam"]["guard"]["q_resize"]);
    REQUIRE(rep["reparam"]["guard"]["far"].is_object());
    CHECK(row["q_far_resize"] == rep["reparam"]["guard"]["far"]["q_resize"]);
    CHECK(row["q_far"] == rep["reparam"]["guard"]["far"][row["written"] == "resize" ? "q_resize" : "q_reparam"]);
    CHECK(test::validate_gltf(out / (name + ".glb"))["numErrors"] == 0);
  }

  // Resume: the good ones are skipped, the broken one is retried.
  r = run_uvpress(cmd);
  CHECK(r.exit_code == 1);
  CHECK_THAT(r.out, Catch::Contains("0 ok, 3 skipped, 1 failed"));
  // A changed input is redone; so is every asset when the options change.
  io::save_gltf(pipeline::make_demo_asset({9, 32}), assets[1].string());
  r = run_uvpress(cmd);
  CHECK_THAT(r.out, Catch::Contains("1 ok, 2 skipped, 1 failed"));
  r = run_uvpress(cmd + " --cost 0.3 --jobs 2");
  CHECK_THAT(r.out, Catch::Contains("3 ok, 0 skipped, 1 failed"));
  CHECK(read_json(out / "asset0.report.json")["options"]["cost"] == 0.3);
  // A corrupted output is redone, not trusted.
  std::ofstream(out / "asset2.glb", std::ios::binary | std::ios::app) << "x";
  r = run_uvpress(cmd + " --cost 0.3");
  CHECK_THAT(r.out, Catch::Contains("1 ok, 2 skipped, 1 failed"));
  // An output written by an older algorithm (its report says so) is redone.
  {
    json old = read_json(out / "asset1.report.json");
    REQUIRE(old["options"]["algorithm"] == pipeline::kReparamRevision);
    old["options"]["algorithm"] = pipeline::kReparamRevision - 1;
    std::ofstream(out / "asset1.report.json") << old.dump(2);
  }
  r = run_uvpress(cmd + " --cost 0.3");
  CHECK_THAT(r.out, Catch::Contains("1 ok, 2 skipped, 1 failed"));

  // Options recorded only where they differ from reparam's defaults still mark every
  // output stale: the guard turned off, and an explicit --epsilon equal to the default
  // (it turns rate control off, a different result). batch takes reparam's options.
  r = run_uvpress(cmd + " --cost 0.3 --force-reparam");
  CHECK_THAT(r.out, Catch::Contains("3 ok, 0 skipped, 1 failed"));
  CHECK(read_json(out / "asset0.report.json")["options"]["guard"] == false);
  CHECK_FALSE(read_json(out / "asset0.report.json")["options"].contains("rate_control"));
  r = run_uvpress(cmd + " --cost 0.3 --epsilon 0.01 --no-candidates --resample-all --view-texels-per-pixel 0.5");
  CHECK_THAT(r.out, Catch::Contains("3 ok, 0 skipped, 1 failed"));
  {
    const json opts = read_json(out / "asset0.report.json")["options"];
    CHECK(opts["rate_control"] == false);
    CHECK(opts["candidates"] == false);
    CHECK(opts["exact_texels"] == false);
    CHECK(opts["view_texels_per_pixel"] == 0.5);
    CHECK_FALSE(opts.contains("guard"));
  }
  r = run_uvpress(cmd + " --cost 0.3 --epsilon 0.01 --no-candidates --resample-all --view-texels-per-pixel 0.5");
  CHECK_THAT(r.out, Catch::Contains("0 ok, 3 skipped, 1 failed"));

  // Usage errors exit 2.
  CHECK(run_uvpress(cmd + " --shard-index 2 --shard-count 2").exit_code == 2);
  CHECK(run_uvpress("batch -o x").exit_code == 2);
  // A missing manifest is an input error naming it.
  auto m = run_uvpress("batch --manifest " + quoted(dir / "nope.txt") + " -o " + quoted(out));
  CHECK(m.exit_code == 1);
  CHECK_THAT(m.err, Catch::Contains("nope.txt"));
}

TEST_CASE("batch: shards from flags and from SLURM_ARRAY_TASK_ID cover the manifest once, --collect merges", "[batch][cli]") {
  test::Scratch dir("batch-shards");
  write_assets(dir.path(), 3);
  test::write_lines(dir / "list.txt", {"in/asset0.glb", "in/asset1.glb", "in/asset2.glb"});
  auto out = dir / "out";
  const std::string base = "batch --manifest " + quoted(dir / "list.txt") + " -o " + quoted(out) + " --no-optimize --device cpu";
  auto a = run_uvpress(base + " --shard-index 0 --shard-count 2");
  CHECK(a.exit_code == 0);
  auto s0 = read_json(out / "summary-shard-0-of-2.json");
  CHECK(s0["assets"].size() == 2);
  // One asset per index from the environment (no count: one asset per index).
  CHECK(run_uvpress_env("SLURM_ARRAY_TASK_ID=1", base) == 0);
  auto s1 = read_json(out / "summary-shard-1-of-3.json");
  REQUIRE(s1["assets"].size() == 1);
  CHECK(s1["assets"][0]["name"] == "asset1");
  auto c = run_uvpress(base + " --collect");
  CHECK(c.exit_code == 0);
  auto all = read_json(out / "summary.json");
  CHECK(all["counts"]["ok"] == 3);
}

TEST_CASE("batch: SIGKILL mid-way, then resume: every output complete and valid", "[batch][kill]") {
  test::Scratch dir("batch-kill");
  const int n = 8;
  write_assets(dir.path(), n, 24, 512);
  std::vector<std::string> lines;
  for (int k = 0; k < n; ++k) lines.push_back("in/asset" + std::to_string(k) + ".glb");
  test::write_lines(dir / "list.txt", lines);
  auto out = dir / "out";
  const std::string manifest = (dir / "list.txt").string(), out_dir = out.string();

  auto check_consistent = [&](const char* when) {
    // Every output that exists loads whole; every "ok" report matches its output.
    size_t ok = 0;
    if (!test::fs::exists(out)) return ok;
    for (auto& e : test::fs::directory_iterator(out)) {
      auto name = e.path().filename().string();
      INFO(when << ": " << name);
      if (e.path().extension() == ".glb" && name[0] != '.') CHECK_NOTHROW(io::load_gltf(e.path().string()));
      if (name.size() > 12 && name.substr(name.size() - 12) == ".report.json") {
        auto rep = read_json(e.path());
        if (rep["status"] == "ok") {
          ++ok;
          CHECK(rep["output_hash"] == batch::hash_asset(rep["output"].get<std::string>()));
        }
      }
    }
    return ok;
  };

  size_t kills = 0, done_at_kill = 0;
  std::vector<size_t> done_after_kill;
  for (int round = 0; round < 2; ++round) {
    std::vector<std::string> args = {UVPRESS_BINARY, "batch", "--manifest", manifest, "-o", out_dir, "--no-optimize", "--score-resolution", "512",
                                     "--device", "cpu", "--jobs", round == 1 ? "2" : "1"};
    std::vector<char*> argv;
    for (auto& s : args) argv.push_back(s.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
    pid_t pid;
    REQUIRE(posix_spawn(&pid, UVPRESS_BINARY, &fa, nullptr, argv.data(), environ) == 0);
    posix_spawn_file_actions_destroy(&fa);
    // Kill once this round has finished one more asset, mid-way through the next.
    const size_t before = check_consistent("before");
    int status = 0;
    bool exited = false;
    for (int t = 0; t < 3000 && !exited; ++t) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      if (waitpid(pid, &status, WNOHANG) == pid) exited = true;
      else if (check_consistent("running") > before) break;
    }
    if (!exited) {
      std::this_thread::sleep_for(std::chrono::milliseconds(40 + 30 * round));
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      ++kills;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));  // workers die with the batch
    done_at_kill = check_consistent("after the kill");
    if (!exited) done_after_kill.push_back(done_at_kill);
  }
  REQUIRE(kills >= 1);
  CHECK(done_after_kill.front() < size_t(n));  // killed mid-way
  // Resume to the end.
  // The same options (the resume skips only assets done with them).
  auto r = run_uvpress("batch --manifest " + quoted(test::fs::path(manifest)) + " -o " + quoted(out) +
                       " --no-optimize --score-resolution 512 --device cpu");
  INFO(r.out << r.err);
  CHECK(r.exit_code == 0);
  auto summary = read_json(out / "summary.json");
  CHECK(summary["counts"]["failed"] == 0);
  CHECK(summary["counts"]["ok"].get<int>() + summary["counts"]["skipped"].get<int>() == n);
  CHECK(summary["counts"]["skipped"].get<size_t>() >= done_at_kill);
  CHECK(check_consistent("resumed") == size_t(n));
  for (int k = 0; k < n; ++k) CHECK(test::validate_gltf(out / ("asset" + std::to_string(k) + ".glb"))["numErrors"] == 0);
  size_t temporaries = 0;
  for (auto& e : test::fs::directory_iterator(out)) temporaries += e.path().filename().string()[0] == '.';
  std::string after;
  for (size_t d : done_after_kill) after += (after.empty() ? "" : ", ") + std::to_string(d);
  WARN("kill and resume: " << kills << " SIGKILLs (assets done after each: " << after << " of " << n << "), "
                           << done_at_kill << "/" << n << " done before the resume, all " << n << " complete and valid after it; " << temporaries
                           << " orphaned temporaries (never renamed into place)");
}

TEST_CASE("batch --texture-format astc: KTX2 copies beside each output, in its hash and report, resume redoes a lost copy",
          "[batch][cli][astc]") {
  test::Scratch dir("batch-astc");
  write_assets(dir.path(), 2, 6, 48);
  test::write_lines(dir / "list.txt", {"in/asset0.glb", "in/asset1.glb"});
  const auto out = dir / "out";
  const std::string cmd = "batch --manifest " + quoted(dir / "list.txt") + " -o " + quoted(out) + " --no-optimize --device cpu";

  auto r = run_uvpress(cmd + " --texture-format astc --astc-block 4x4");
  INFO(r.out << r.err);
  REQUIRE(r.exit_code == 0);
  std::vector<test::fs::path> copies;
  for (const char* name : {"asset0", "asset1"}) {
    const auto glb = out / (std::string(name) + ".glb");
    const auto rep = read_json(out / (std::string(name) + ".report.json"));
    CHECK(rep["options"]["texture_format"]["astc"] == "4x4");
    // --block-align follows a square ASTC footprint unless given.
    CHECK(rep["options"]["block"] == 4);
    const auto refs = io::ktx2_sidecar_refs(io::read_file(glb.string()));
    const auto& gpu = rep["reparam"]["gpu_textures"];
    REQUIRE(gpu.is_array());
    REQUIRE(gpu.size() == refs.size());
    REQUIRE(refs.size() == io::load_gltf(glb.string()).image_bytes.size());
    for (size_t k = 0; k < refs.size(); ++k) {
      const auto ktx2 = out / refs[k].uri;
      REQUIRE(test::fs::exists(ktx2));
      CHECK(refs[k].uri.rfind(name, 0) == 0);  // named for the asset, so that names never collide
      CHECK(gpu[k]["bytes"] == test::fs::file_size(ktx2));
      const auto bytes = io::read_file(ktx2.string());
      const uint8_t magic[12] = {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n'};
      REQUIRE(bytes.size() > 16);
      CHECK(std::equal(magic, magic + 12, bytes.begin()));
      uint32_t vk_format = 0;
      std::memcpy(&vk_format, bytes.data() + 12, 4);
      CHECK(vk_format == gpu[k]["vk_format"]);
      copies.push_back(ktx2);
    }
    CHECK(rep["output_hash"] == batch::hash_asset(glb.string()));
    CHECK(test::validate_gltf(glb)["numErrors"] == 0);
  }
  REQUIRE(copies.size() >= 2);

  // Up to date: skipped. A lost or changed KTX2 copy makes its asset's output stale.
  r = run_uvpress(cmd + " --texture-format astc --astc-block 4x4");
  CHECK_THAT(r.out, Catch::Contains("0 ok, 2 skipped"));
  test::fs::remove(copies[0]);
  std::ofstream(copies.back(), std::ios::binary | std::ios::app) << "x";
  r = run_uvpress(cmd + " --texture-format astc --astc-block 4x4");
  CHECK_THAT(r.out, Catch::Contains("2 ok, 0 skipped"));
  CHECK(test::fs::exists(copies[0]));

  // Back to the source format: the outputs are redone and the copies they no longer name removed.
  r = run_uvpress(cmd);
  CHECK_THAT(r.out, Catch::Contains("2 ok, 0 skipped"));
  for (const auto& c : copies) CHECK_FALSE(test::fs::exists(c));
  CHECK(read_json(out / "asset0.report.json")["options"]["texture_format"] == "source");
}

TEST_CASE("batch --strict: an asset that breaks the glTF rules fails, without it the row carries the count", "[batch][cli][rules]") {
  test::Scratch dir("batch-strict");
  auto assets = write_assets(dir.path(), 1);
  // Declared UV bounds above every value: two ACCESSOR_MAX_MISMATCH, nothing else wrong.
  io::GltfFile bad = pipeline::make_demo_asset({6, 32});
  const int uv = bad.model.meshes[0].primitives[0].attributes.at("TEXCOORD_0");
  bad.model.accessors[size_t(uv)].maxValues = {1.5, 1.5};
  io::save_gltf(bad, (dir / "in" / "bounds.glb").string());
  test::write_lines(dir / "list.txt", {"in/asset0.glb", "in/bounds.glb"});
  auto out = dir / "out";
  const std::string cmd = "batch --manifest " + quoted(dir / "list.txt") + " -o " + quoted(out) + " --no-optimize --device cpu";

  auto r = run_uvpress(cmd);
  INFO(r.out << r.err);
  CHECK(r.exit_code == 0);
  auto rep = read_json(out / "bounds.report.json");
  CHECK(rep["status"] == "ok");
  CHECK(rep["input_validation"]["errors"] == 2);
  CHECK(rep["input_validation"]["codes"]["ACCESSOR_MAX_MISMATCH"] == 2);
  CHECK_THAT(rep["warnings"].dump(), Catch::Contains("2 glTF validation errors"));
  CHECK(read_json(out / "asset0.report.json")["input_validation"]["errors"] == 0);
  CHECK_FALSE(read_json(out / "asset0.report.json")["options"].contains("strict"));

  // --strict is part of the options (both are redone), and the bad asset fails, named.
  r = run_uvpress(cmd + " --strict");
  CHECK(r.exit_code == 1);
  CHECK_THAT(r.out, Catch::Contains("1 ok, 0 skipped, 1 failed"));
  rep = read_json(out / "bounds.report.json");
  CHECK(rep["status"] == "failed");
  CHECK_THAT(rep["error"].get<std::string>(), Catch::Contains("bounds.glb") && Catch::Contains("refused (--strict)"));
  CHECK(read_json(out / "asset0.report.json")["options"]["strict"] == true);
}
