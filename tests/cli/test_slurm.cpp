// Cluster integration: a one-node Slurm cluster on loopback (tools/slurm/loopback-cluster.sh)
// runs tools/slurm/uvpress-array.sbatch as an array over four assets, one broken: the good
// tasks end COMPLETED with valid outputs, the broken one FAILED with its reason in its
// report. Skips, saying why, when the daemons cannot start (not root, packages missing).
#include <catch2/catch.hpp>

#include "io/gltf_io.h"
#include "pipeline/demo_asset.h"
#include "support.h"

#include <fstream>
#include <regex>
#include <sys/wait.h>

using namespace uvpress;
using json = nlohmann::json;

namespace {

struct Shell {
  int code;
  std::string out;
};

Shell sh(const std::string& command) {
  Shell r{-1, ""};
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (!p) return r;
  char buf[4096];
  for (size_t n; (n = fread(buf, 1, sizeof buf, p)) > 0;) r.out.append(buf, n);
  int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

std::string q(const test::fs::path& p) { return "'" + p.string() + "'"; }

}  // namespace

TEST_CASE("batch: Slurm array on a loopback cluster (COMPLETED / FAILED per task)", "[batch][slurm]") {
  test::Scratch dir("slurm");
  const test::fs::path tools = test::fs::path(UVPRESS_SOURCE_DIR) / "tools" / "slurm";
  const test::fs::path cluster = dir / "cluster";
  auto up = sh(q(tools / "loopback-cluster.sh") + " start " + q(cluster));
  struct Down {
    std::string cmd;
    ~Down() { sh(cmd); }
  } down{q(tools / "loopback-cluster.sh") + " stop " + q(cluster)};
  if (up.code == 77) UVPRESS_SKIP("no Slurm cluster on loopback: " + up.out);
  REQUIRE(up.code == 0);

  test::fs::create_directories(dir / "in");
  test::fs::create_directories(dir / "logs");
  for (int k = 0; k < 3; ++k)
    io::save_gltf(pipeline::make_demo_asset({6 + k, 32}), (dir / "in" / ("good" + std::to_string(k) + ".glb")).string());
  std::ofstream(dir / "in" / "broken.glb") << "glTF, but truncated";
  std::ofstream(dir / "assets.txt") << "in/good0.glb\nin/broken.glb\nin/good1.glb\nin/good2.glb\n";

  // The template as shipped; the loopback node is small, so ask for less CPU and memory.
  const std::string env = "SLURM_CONF=" + q(cluster / "slurm.conf") + " UVPRESS=" + q(UVPRESS_BINARY);
  auto sub = sh("cd " + q(dir.path()) + " && " + env + " timeout 240 sbatch --wait --parsable --cpus-per-task=1 --mem=500M" +
                " --array=0-3 " + q(tools / "uvpress-array.sbatch") + " assets.txt out --no-optimize --device cpu");
  INFO(sub.out);
  CHECK(sub.code == 1);  // sbatch --wait: the highest exit code of the array's tasks
  std::smatch m;
  REQUIRE(std::regex_search(sub.out, m, std::regex("^([0-9]+)", std::regex::multiline)));
  const std::string job = m[1];

  const char* names[] = {"good0", "broken", "good1", "good2"};
  std::string states;
  for (int t = 0; t < 4; ++t) {
    auto show = sh(env + " scontrol show job " + job + "_" + std::to_string(t));
    INFO(show.out);
    std::smatch s;
    REQUIRE(std::regex_search(show.out, s, std::regex("JobState=([A-Z_]+)")));
    states += std::string(t ? ", " : "") + names[t] + " " + s[1].str();
    const auto log = dir / "logs" / ("uvpress-" + job + "_" + std::to_string(t) + ".log");
    CHECK(test::fs::exists(log));  // one log per task
    auto report = json::parse(std::ifstream(dir / "out" / (std::string(names[t]) + ".report.json")));
    if (t == 1) {
      CHECK(s[1] == "FAILED");
      CHECK(report["status"] == "failed");
      CHECK_THAT(report["error"].get<std::string>(), Catch::Contains("broken.glb"));
      CHECK_FALSE(test::fs::exists(dir / "out" / "broken.glb"));
    } else {
      CHECK(s[1] == "COMPLETED");
      CHECK(report["status"] == "ok");
      CHECK(test::validate_gltf(dir / "out" / (std::string(names[t]) + ".glb"))["numErrors"] == 0);
    }
  }
  // The whole array's summary from the reports.
  auto collect = test::run_uvpress("batch --manifest " + q(dir / "assets.txt") + " -o " + q(dir / "out") + " --collect");
  CHECK(collect.exit_code == 1);
  auto summary = json::parse(std::ifstream(dir / "out" / "summary.json"));
  CHECK(summary["counts"]["ok"] == 3);
  CHECK(summary["counts"]["failed"] == 1);
  WARN("Slurm array " << job << " on loopback: " << states);
}
