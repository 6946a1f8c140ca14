// `fabatlas import-scad` and MODEL.scad given to eval and sample, as a user
// runs them: files written, warnings naming lines, exit status 2 with one line.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "fabatlas/storage/job_store.h"

#include "fabatlas/testing/command_run.h"
#include "fabatlas/testing/paths.h"

namespace {

using fabatlas::testing::CommandRun;
using fabatlas::testing::Fabatlas;

TEST(ScadCli, ImportWritesDesignAndJobAndNamesMalformedLines) {
  auto dir = fabatlas::testing::FreshTempDir("scad-cli");
  std::ofstream(dir / "box.scad") << "// Edge length\nsize = 10; // [5:20]\nbad = 3; // [9:1]\ncube(size);\n";
  CommandRun r = Fabatlas("import-scad box.scad --out box.yaml", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("box.scad:3: parameter 'bad'"), std::string::npos) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "box.yaml"));
  EXPECT_TRUE(std::filesystem::exists(dir / "box.job.yaml"));
  CommandRun v = Fabatlas("validate box.yaml", dir);
  EXPECT_EQ(v.status, 0) << v.err;

  CommandRun e = Fabatlas("eval box.scad --at size=12 --json", dir);
  ASSERT_EQ(e.status, 0) << e.err;
  auto j = nlohmann::json::parse(e.out);
  EXPECT_NEAR(j["properties"]["volume"].get<double>(), 1728, 0.01 * 1728);

  CommandRun bad = Fabatlas("import-scad box.scad --out x.yaml --expose nope", dir);
  EXPECT_EQ(bad.status, 2);
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
  EXPECT_NE(bad.err.find("box.scad: --expose nope"), std::string::npos) << bad.err;
  CommandRun missing = Fabatlas("eval nothere.scad", dir);
  EXPECT_EQ(missing.status, 2);
  EXPECT_NE(missing.err.find("nothere.scad"), std::string::npos) << missing.err;
}

TEST(ScadCli, SampleAModelDirectly) {
  auto dir = fabatlas::testing::FreshTempDir("scad-cli-sample");
  std::ofstream(dir / "slab.scad") << "n = 2; // [1:3]\nshape = \"flat\"; // [flat, tall]\n"
                                      "cube([10 * n, 10, shape == \"tall\" ? 8 : 4]);\n";
  CommandRun r = Fabatlas("sample slab.scad --out out", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "out/model/slab.yaml"));
  std::ifstream form(dir / "out/form.json");
  auto j = nlohmann::json::parse(form);
  ASSERT_TRUE(j.contains("samples"));
  // Every sample's volume is the cube's: 10 n * 10 * (4 or 8).
  int checked = 0;
  for (const auto& s : j["samples"]) {
    if (!s.value("valid", false)) continue;
    const double n = s["u"][0].get<double>();                 // dimensions in order: n, shape
    const double h = s["u"][1].get<double>() == 1 ? 8 : 4;  // enum index: flat, tall
    EXPECT_NEAR(s["properties"]["volume"].get<double>(), 100 * n * h, 0.02 * 100 * n * h);
    ++checked;
  }
  EXPECT_GE(checked, 6);
}

// A wall one nozzle wide (0.4 mm, tilted) is the model's own surface on the
// mesh road: closed, manifold and free of self-intersections (watertight
// passes, as OpenSCAD renders it), and thinner than min_thickness's 0.8 mm,
// which is the verdict (thin_parts); the level-set road at 0.5 mm voxels
// folded its extraction there or lost the wall ("the tree produced no
// material", issue 30). At 1 mm both checks pass.
TEST(ScadCli, AWallThinnerThanTheMinimumIsAThinPartNotAFold) {
  auto dir = fabatlas::testing::FreshTempDir("scad-cli-fold");
  std::ofstream(dir / "fin.scad") << "t = 1; // [0.2:0.1:2]\n"
                                     "cube([20, 20, 2]);\n"
                                     "translate([8, 2, 1]) rotate([0, 30, 10]) cube([t, 14, 10]);\n";
  CommandRun thin = Fabatlas("eval fin.scad --at t=0.4 --json", dir);
  ASSERT_EQ(thin.status, 0) << thin.err;
  const auto j = nlohmann::json::parse(thin.out);
  ASSERT_TRUE(j["checks"].contains("watertight")) << thin.out;
  EXPECT_TRUE(j["checks"]["watertight"]["passed"].get<bool>()) << j["checks"]["watertight"]["reason"];
  EXPECT_FALSE(j["checks"]["min_thickness"]["passed"].get<bool>()) << thin.out;
  EXPECT_EQ(j["failure"], "thin_parts") << thin.out;
  CommandRun thick = Fabatlas("eval fin.scad --at t=1 --json", dir);
  ASSERT_EQ(thick.status, 0) << thick.err;
  const auto k = nlohmann::json::parse(thick.out);
  EXPECT_TRUE(k["checks"]["watertight"]["passed"].get<bool>()) << thick.out;
  EXPECT_TRUE(k["checks"]["min_thickness"]["passed"].get<bool>()) << thick.out;
}

// A cluster job (`fabatlas run`: a coordinator and a worker process over
// gRPC) on a model whose samples share a CSG subtree: the drilled slab's
// union of two cubes is the same at every radius, so the worker finds it in
// its cache from the second sample on. Every sample must still list every
// descendant of every subtree it lists (the store's sample -> subtree keys
// relation is closed under children): the cache plan may keep a child of a
// hit, and the coordinator takes a kept subtree's geometry from a valid
// sample listing it. Before, a hit was recorded without its descendants, so
// the union's cubes were listed only by the samples that computed them.
TEST(ScadCli, ClusterRunRecordsTheDescendantsOfCachedCsgSubtrees) {
  auto dir = fabatlas::testing::FreshTempDir("scad-cli-run");
  std::ofstream(dir / "drilled.scad") << "r = 2; // [1:4]\n"
                                         "difference() {\n"
                                         "  union() { cube([20, 20, 10]); translate([5, 5, 10]) cube([10, 10, 5]); }\n"
                                         "  translate([10, 10, -1]) cylinder(r = r, h = 20, $fn = 24);\n"
                                         "}\n";
  // A worker's cache keeps only subtrees whose root took at least the job's
  // cache.min_subtree_seconds (default 0.1 s, more than these cubes take):
  // the job beside the imported design keeps every subtree.
  CommandRun import = Fabatlas("import-scad drilled.scad --out drilled.yaml", dir);
  ASSERT_EQ(import.status, 0) << import.err;
  std::ofstream(dir / "drilled.job.yaml", std::ios::app) << "cache: {min_subtree_seconds: 0}\n";
  CommandRun r = Fabatlas("run drilled.job.yaml --workers 1 --slots 1 --quiet --out out", dir);
  ASSERT_EQ(r.status, 0) << r.err;

  fabatlas::storage::JobStore store(dir / "out/cluster-state/state.db");
  const auto jobs = store.Jobs();
  ASSERT_EQ(jobs.size(), 1u);
  std::map<std::string, std::vector<std::string>> children;
  int hits = 0;
  for (const auto& row : store.Subtrees(jobs[0].id)) {
    children[row.key] = row.children;
    hits += row.uses > row.seconds_count;  // found in the worker's cache at least once
  }
  EXPECT_GT(hits, 0);  // the union of cubes, at least
  const auto samples = store.SampleSubtreeKeys(jobs[0].id);
  EXPECT_GE(samples.size(), 4u);
  for (const auto& s : samples) {
    const std::set<std::string> listed(s.subtree_keys.begin(), s.subtree_keys.end());
    for (const auto& key : s.subtree_keys)
      for (const auto& child : children[key])
        EXPECT_TRUE(listed.count(child)) << "sample " << s.point_key << " lists " << key.substr(0, 8)
                                         << " without its child " << child.substr(0, 8);
  }
}

}  // namespace
