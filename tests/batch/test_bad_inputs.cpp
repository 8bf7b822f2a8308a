// The bad-input corpus (issue 8): every malformed asset gives exit 1 with one stderr line
// naming the file and the reason, or a documented graceful path (exit 0, a valid output,
// warnings only); never a crash, never a partial output. CI also runs this file's tests
// against an AddressSanitizer + UBSan build of uvpress (.ci/run).
#include <catch2/catch.hpp>

#include "batch/corpus.h"
#include "support.h"

#include <fstream>

using namespace uvpress;
using test::run_uvpress;

namespace {

std::string quoted(const test::fs::path& p) { return "'" + p.string() + "'"; }

std::vector<std::string> entries(const test::fs::path& dir) {
  std::vector<std::string> out;
  for (auto& e : test::fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
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
    check_case(c, "reparam " + quoted(c.file) + " -o " + quoted(output) + " --no-optimize --device cpu", out_dir, output);
    (test::fs::exists(output) ? graceful : failed) += 1;
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
                       " --no-optimize --device cpu --jobs 2");
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
}
