// The bad-input corpus (issue 8): every malformed asset gives exit 1 with one stderr line
// naming the file and the reason, or a documented graceful path (exit 0, a valid output,
// warnings only); never a crash, never a partial output. CI also runs this file's tests
// against an AddressSanitizer + UBSan build of uvpress (.ci/run).
#include <catch2/catch.hpp>

#include "batch/corpus.h"
#include "support.h"

#include <fstream>
#include <string>

using namespace uvpress;
using test::run_uvpress;

namespace {

using test::quoted;

std::vector<std::string> entries(const test::fs::path& dir) {
  std::vector<std::string> out;
  for (auto& e : test::fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

// Files under `dir` holding the bytes planted outside the uploads folder (issue 13).
std::vector<std::string> files_with_marker(const test::fs::path& dir) {
  std::vector<std::string> out;
  for (auto& e : test::fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::ifstream in(e.path(), std::ios::binary);
    const std::string bytes(std::istreambuf_iterator<char>(in), {});
    if (bytes.find(test::kOutsideMarker) != std::string::npos) out.push_back(e.path().string());
  }
  return out;
}

// Checks one run of uvpress on a corpus case; `out` is an empty folder for its output.
void check_case(const test::CorpusCase& c, const std::string& command, const test::fs::path& out_dir,
                const test::fs::path& output) {
  auto r = run_uvpress(command);
  INFO("case " << c.name << ": uvpress " << command << "\nexit " << r.exit_code << "\nstderr: " << r.err);
  // A crash (signal, sanitizer report) shows as an exit code other than 0 and 1, or as
  // sanitizer text on stderr.
  REQUIRE((r.exit_code == 0 || r.exit_code == 1));
  CHECK(r.err.find("Sanitizer") == std::string::npos);
  CHECK(r.err.find("runtime error") == std::string::npos);
  auto lines = r.err_lines();
  if (r.exit_code == 1) {
    CHECK_FALSE(c.graceful);
    REQUIRE(lines.size() == 1);
    CHECK_THAT(lines[0], Catch::StartsWith("uvpress: " + c.file.string() + ": "));
    CHECK(lines[0].size() > ("uvpress: " + c.file.string() + ": ").size() + 3);  // a reason
    CHECK_THAT(lines[0], Catch::Contains(c.reason));
    CHECK(entries(out_dir).empty());  // no output, no temporaries
  } else {
    CHECK(c.graceful);
    for (const auto& l : lines) CHECK_THAT(l, Catch::Contains("warning"));
    REQUIRE(test::fs::exists(output));
    auto v = test::validate_gltf(output);
    INFO(v.dump());
    CHECK(v["numErrors"] == 0);
  }
}

}  // namespace

TEST_CASE("bad inputs: each malformed asset fails with one line naming it, or degrades gracefully", "[batch][corpus]") {
  test::Scratch dir("corpus");
  auto corpus = test::make_bad_input_corpus(dir.path());
  REQUIRE(corpus.size() >= 30);
  size_t failed = 0, graceful = 0;
  for (const auto& c : corpus) {
    auto out_dir = dir / ("out-" + c.name);
    test::fs::create_directories(out_dir);
    auto output = out_dir / "out.glb";
    // Errors, not quality: eval's fixed 512-px views (the auto ones cost 4-16x under ASan).
    check_case(c, "reparam " + quoted(c.file) + " -o " + quoted(output) + " --no-optimize --score-resolution 512 --device cpu", out_dir, output);
    (test::fs::exists(output) ? graceful : failed) += 1;
    CHECK(files_with_marker(out_dir).empty());
    test::fs::remove_all(out_dir);
    // info reads the same structures without writing anything.
    auto r = run_uvpress("info " + quoted(c.file));
    INFO("info " << c.name << ": exit " << r.exit_code << "\n" << r.err);
    CHECK((r.exit_code == 0 || r.exit_code == 1));
    if (r.exit_code == 1) CHECK(r.err_lines().size() == 1);
  }
  WARN("bad-input corpus: " << corpus.size() << " inputs, " << failed << " rejected with a reason, " << graceful
                            << " graceful, 0 crashes, 0 partial outputs");
}

TEST_CASE("bad inputs: a batch over the whole corpus reports every failure and writes nothing partial", "[batch][corpus]") {
  test::Scratch dir("corpus-batch");
  auto corpus = test::make_bad_input_corpus(dir.path());
  {
    std::ofstream m(dir / "manifest.txt");
    m << "# the bad-input corpus\n";
    for (const auto& c : corpus) m << test::fs::relative(c.file, dir.path()).string() << "\n";
  }
  auto out = dir / "out";
  auto r = run_uvpress("batch --manifest " + quoted(dir / "manifest.txt") + " -o " + quoted(out) +
                       " --no-optimize --score-resolution 512 --device cpu --jobs 2");
  INFO(r.out << "\n" << r.err);
  CHECK(r.exit_code == 1);
  auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  REQUIRE(summary["assets"].size() == corpus.size());
  for (size_t k = 0; k < corpus.size(); ++k) {
    const auto& c = corpus[k];
    const auto& a = summary["assets"][k];
    INFO(c.name << ": " << a.dump());
    auto report = nlohmann::json::parse(std::ifstream(out / (a["name"].get<std::string>() + ".report.json")));
    if (a["status"] == "failed") {
      CHECK_FALSE(c.graceful);
      CHECK_THAT(report["error"].get<std::string>(), Catch::Contains(c.name) && Catch::Contains(c.reason));
      CHECK_FALSE(test::fs::exists(out / (a["name"].get<std::string>() + ".glb")));
    } else {
      CHECK(a["status"] == "ok");
      CHECK(c.graceful);
      CHECK(test::validate_gltf(out / (a["name"].get<std::string>() + ".glb"))["numErrors"] == 0);
    }
  }
  for (const auto& f : entries(out)) CHECK_FALSE(f.rfind(".", 0) == 0);  // no temporaries left
  CHECK(files_with_marker(out).empty());  // reports name references, never their bytes
}

TEST_CASE("bad inputs: copy carries no reference case and no byte from outside the asset's folder", "[batch][corpus]") {
  // copy keeps every image byte for byte: the command that pulled ../../etc/hostname into
  // its output before issue 13.
  test::Scratch dir("corpus-copy");
  auto corpus = test::make_bad_input_corpus(dir.path());
  size_t references = 0;
  for (const auto& c : corpus) {
    if (c.name.rfind("ref-", 0) != 0 && c.name.rfind("image-", 0) != 0) continue;
    ++references;
    auto out_dir = dir / ("out-" + c.name);
    test::fs::create_directories(out_dir);
    for (const char* ext : {".gltf", ".glb"}) {
      auto output = out_dir / (std::string("out") + ext);
      auto r = run_uvpress("copy " + quoted(c.file) + " -o " + quoted(output));
      INFO("case " << c.name << ": copy to " << ext << "\nexit " << r.exit_code << "\nstderr: " << r.err);
      CHECK(r.exit_code == 1);
      auto lines = r.err_lines();
      REQUIRE(lines.size() == 1);
      CHECK_THAT(lines[0], Catch::StartsWith("uvpress: " + c.file.string() + ": ") && Catch::Contains(c.reason));
      CHECK(entries(out_dir).empty());
    }
    test::fs::remove_all(out_dir);
  }
  CHECK(references >= 25);
}

TEST_CASE("bad inputs: --allow-outside-refs restores reading a trusted layout's shared files", "[batch][corpus][cli]") {
  // A studio layout: assets in their own folders, textures shared in a sibling folder.
  test::Scratch dir("trusted");
  test::fs::create_directories(dir / "textures");
  test::fs::create_directories(dir / "assets");
  test::fs::create_directories(dir / "out");
  {
  }
  auto corpus_dir = dir / "corpus";
  test::fs::create_directories(corpus_dir);
  test::make_bad_input_corpus(corpus_dir);
  test::fs::copy_file(corpus_dir / "secret.png", dir / "textures" / "shared.png");  // the demo texture + marker
  nlohmann::json j = nlohmann::json::parse(std::ifstream(corpus_dir / "good.gltf"));
  test::fs::copy_file(corpus_dir / j["buffers"][0]["uri"].get<std::string>(), dir / "assets" / j["buffers"][0]["uri"].get<std::string>());
  j["images"][0] = {{"uri", "../textures/shared.png"}};
  const auto asset = dir / "assets" / "crate.gltf";
  std::ofstream(asset) << j.dump(1);

  // By default: refused, nothing written.
  test::check_input_error(dir, "copy " + quoted(asset) + " -o " + quoted(dir / "out" / "crate.glb"), asset,
                          "image 0: '../textures/shared.png' points outside the asset's folder");
  CHECK(entries(dir / "out").empty());

  // Opted out: today's behaviour, the shared texture carried byte for byte, a valid asset.
  for (const std::string flags : {"--allow-outside-refs copy", "copy --allow-outside-refs"}) {
    auto r = run_uvpress(flags + " " + quoted(asset) + " -o " + quoted(dir / "out" / "crate.glb"));
    INFO(flags << ": " << r.err);
    CHECK(r.exit_code == 0);
    CHECK(files_with_marker(dir / "out").size() == 1);
    CHECK(test::validate_gltf(dir / "out" / "crate.glb")["numErrors"] == 0);
    test::fs::remove(dir / "out" / "crate.glb");
  }

  // The other checks still hold when opted out: a device is not a file.
  j["images"][0] = {{"uri", "/dev/zero"}};
  const auto device = dir / "assets" / "device.gltf";
  std::ofstream(device) << j.dump(1);
  test::check_input_error(dir, "--allow-outside-refs copy " + quoted(device) + " -o " + quoted(dir / "out" / "d.glb"), device,
                          "image 0: '/dev/zero' is a device, not a regular file");

  // batch passes it through and records it: a run with it is not a resume of one without.
  std::ofstream(dir / "manifest.txt") << "assets/crate.gltf\n";
  auto batch = [&](const std::string& flag) {
    return run_uvpress("batch --manifest " + quoted(dir / "manifest.txt") + " -o " + quoted(dir / "batch") +
                       " --no-optimize --score-resolution 512 --device cpu " + flag);
  };
  auto r = batch("");
  CHECK(r.exit_code == 1);
  auto report = nlohmann::json::parse(std::ifstream(dir / "batch" / "crate.report.json"));
  CHECK_THAT(report["error"].get<std::string>(), Catch::Contains("points outside the asset's folder"));
  CHECK(report["options"]["allow_outside_refs"] == false);
  r = batch("--allow-outside-refs");
  INFO(r.out << r.err);
  CHECK(r.exit_code == 0);
  report = nlohmann::json::parse(std::ifstream(dir / "batch" / "crate.report.json"));
  CHECK(report["status"] == "ok");
  CHECK(report["options"]["allow_outside_refs"] == true);
  r = batch("--allow-outside-refs");  // resumes: same options, same inputs
  CHECK(r.exit_code == 0);
  CHECK_THAT(r.out + r.err, Catch::Contains("skipped"));
}
