// batch's manifest (batch/manifest.h): asset names, shards and the array-index variables
// of Slurm, Kubernetes and AWS Batch.
#include <catch2/catch.hpp>

#include "batch/manifest.h"
#include "support.h"

#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

using namespace uvpress;


TEST_CASE("batch: manifest names, shards and the array-index variables", "[batch]") {
  test::Scratch dir("batch-manifest");
  test::write_lines(dir / "m.txt", {"# comment", "", "a/x.glb", "  b/x.glb  ", "/abs/y.gltf", "z w.glb"});
  auto items = batch::read_manifest((dir / "m.txt").string());
  REQUIRE(items.size() == 4);
  CHECK(items[0].input == (dir / "a/x.glb").string());
  CHECK(items[1].input == (dir / "b/x.glb").string());
  CHECK(items[2].input == "/abs/y.gltf");
  CHECK(items[0].name == "x-1");
  CHECK(items[1].name == "x-2");
  CHECK(items[2].name == "y");
  CHECK(items[3].name == "z_w");
  auto s0 = batch::select_shard(items, 0, 3), s1 = batch::select_shard(items, 1, 3);
  CHECK(s0.size() == 2);
  CHECK(s0[1].position == 3);
  CHECK(s1.size() == 1);
  CHECK_THROWS_AS(batch::select_shard(items, 3, 3), std::invalid_argument);
  test::write_lines(dir / "empty.txt", {"# nothing"});
  CHECK_THROWS(batch::read_manifest((dir / "empty.txt").string()));

  auto env = [](std::map<std::string, std::string> vars) {
    return [vars](const char* n) -> const char* {
      auto it = vars.find(n);
      return it == vars.end() ? nullptr : it->second.c_str();
    };
  };
  auto slurm = batch::shard_from_environment(
      env({{"SLURM_ARRAY_TASK_ID", "7"}, {"SLURM_ARRAY_TASK_MIN", "5"}, {"SLURM_ARRAY_TASK_COUNT", "4"}}));
  CHECK(slurm.index == 2u);
  CHECK(slurm.count == 4u);
  auto k8s = batch::shard_from_environment(env({{"JOB_COMPLETION_INDEX", "3"}}));
  CHECK(k8s.index == 3u);
  CHECK_FALSE(k8s.count);
  CHECK(batch::shard_from_environment(env({{"AWS_BATCH_JOB_ARRAY_INDEX", "0"}})).index == 0u);
  CHECK_FALSE(batch::shard_from_environment(env({})).index);
  CHECK_THROWS_AS(batch::shard_from_environment(env({{"JOB_COMPLETION_INDEX", "x1"}})), std::invalid_argument);
}
