// The two roads of a job publish the same bytes (issue 19): every example
// job of configs/jobs/ run in process (`fabatlas sample`, LocalExecutor) and
// on a cluster (`fabatlas run --workers 2`: an embedded coordinator and two
// worker processes, the remote executor) gives a byte-identical artifact,
// form.json and, for designs with carve_swept nodes, swept_volumes.json and
// swept_<k>.ply. Each job keeps its design, its other sections and its ΔG
// threshold, with a smaller sample budget (1 subdivision, depth 1, at most
// 12 samples past the bootstrap grid) so that the whole set stays within
// minutes, and asks for a geometry cache (opt_max) so that the cache plan's
// two roads are compared too.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <fstream>
#include <string>
#include <vector>

#include "cluster_process.h"

using namespace fabatlas::cluster_test;

namespace {

std::vector<std::string> ExampleJobs() {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(SourceDir() / "configs/jobs"))
    if (e.path().extension() == ".yaml") names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

// The example job with the budget above, written into dir (its design by
// absolute path).
fs::path SmallJob(const std::string& name, const fs::path& dir) {
  const fs::path source = SourceDir() / "configs/jobs" / (name + ".yaml");
  YAML::Node job = YAML::LoadFile(source.string());
  job["design"] = fs::weakly_canonical(source.parent_path() / job["design"].as<std::string>()).string();
  job["sampling"]["subdivisions"] = 1;
  job["sampling"]["max_depth"] = 1;
  job["sampling"]["max_samples"] = 12;
  if (!job["cache"]) job["cache"]["strategy"] = "opt_max";
  const fs::path path = dir / (name + ".yaml");
  YAML::Emitter out;
  out << job;
  std::ofstream(path) << out.c_str() << "\n";
  return path;
}

class Roads : public ::testing::TestWithParam<std::string> {};

TEST_P(Roads, InProcessAndClusterPublishTheSameBytes) {
  const std::string name = GetParam();
  const fs::path dir = FreshDir("roads_" + name);
  const fs::path job = SmallJob(name, dir);
  // Some designs name shared data relative to the repository (the
  // clip-lights family's meshes: ../shared/data/...), as `fabatlas` is run
  // from there.
  fs::current_path(SourceDir());
  const pid_t local =
      Spawn({(BinDir() / "fabatlas").string(), "sample", job.string(), "--out", (dir / "process").string()},
            dir / "process.log");
  ASSERT_EQ(WaitExit(local, std::chrono::minutes(10)), 0) << ReadText(dir / "process.log");
  const pid_t cluster = Spawn({(BinDir() / "fabatlas").string(), "run", job.string(), "--workers", "2", "--out",
                               (dir / "cluster").string(), "--quiet"},
                              dir / "cluster.log");
  ASSERT_EQ(WaitExit(cluster, std::chrono::minutes(10)), 0) << ReadText(dir / "cluster.log");

  std::vector<std::string> compared;
  for (const auto& e : fs::directory_iterator(dir / "process")) {
    const std::string file = e.path().filename().string();
    const bool published = e.path().extension() == ".fabatlas" || file == "form.json" || file == "swept_volumes.json" ||
                           file.rfind("swept_", 0) == 0;
    if (!e.is_regular_file() || !published) continue;
    compared.push_back(file);
    const std::string process = ReadText(e.path()), on_cluster = ReadText(dir / "cluster" / file);
    EXPECT_FALSE(process.empty()) << file;
    EXPECT_TRUE(process == on_cluster) << name << ": " << file << " differs (" << process.size()
                                       << " bytes in process, " << on_cluster.size() << " on the cluster)";
  }
  // The artifact and form.json at least; cabinet_insert's swept volume too.
  EXPECT_GE(compared.size(), 2u);
  if (name == "cabinet_insert") {
    EXPECT_NE(std::find(compared.begin(), compared.end(), "swept_volumes.json"), compared.end());
    EXPECT_NE(std::find(compared.begin(), compared.end(), "swept_0.ply"), compared.end());
  }
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(ExampleJobs, Roads, ::testing::ValuesIn(ExampleJobs()),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

}  // namespace
