// `fabatlas import-scad` and MODEL.scad given to eval and sample, as a user
// runs them: files written, warnings naming lines, exit status 2 with one line.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "fabatlas/mesh/enclosed_volume.h"
#include "fabatlas/mesh/read_mesh.h"
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
    const double n = s["u"][0].get<double>();               // dimensions in order: n, shape
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
  {
    std::ifstream in(dir / "drilled.job.yaml");
    std::string job(std::istreambuf_iterator<char>(in), {});
    const std::string plan = "cache: {strategy: opt_max}";
    ASSERT_NE(job.find(plan), std::string::npos) << job;
    job.replace(job.find(plan), plan.size(), "cache: {strategy: opt_max, min_subtree_seconds: 0}");
    std::ofstream(dir / "drilled.job.yaml") << job;
  }
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

// The 18-parameter organiser (tests/scad/data/organiser.scad) as a user
// imports it: one line per parameter on stdout, --expose with a range for a
// spin box, the design evaluated against OpenSCAD 2021.01's own render at a
// point away from the model's values, and bad input as one line, exit 2.
TEST(ScadCli, ImportAnyModelWithRangesAndABudget) {
  auto dir = fabatlas::testing::FreshTempDir("scad-cli-organiser");
  std::filesystem::copy_file(fabatlas::testing::SourceDir() / "tests/scad/data/organiser.scad", dir / "organiser.scad");
  CommandRun r = Fabatlas("import-scad organiser.scad --out organiser.yaml --voxel 0.5", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 19) << r.out;  // 18 decisions and "wrote ..."
  EXPECT_NE(r.out.find("exposed divider: slider [0.8:0.2:4] in group 'Compartments', within --max-dims 6\n"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("fixed wall = 2: beyond --max-dims 6"), std::string::npos) << r.out;
  CommandRun budget = Fabatlas("import-scad organiser.scad --out b.yaml --voxel 0.5 --max-dims 2", dir);
  ASSERT_EQ(budget.status, 0) << budget.err;
  EXPECT_NE(budget.out.find("(2 exposed: width depth; 16 fixed"), std::string::npos) << budget.out;

  CommandRun ranged = Fabatlas("import-scad organiser.scad --out lip.yaml --voxel 0.5 --expose width,lip=0:3", dir);
  ASSERT_EQ(ranged.status, 0) << ranged.err;
  EXPECT_NE(ranged.out.find("exposed lip: range 0:3 from --expose\n"), std::string::npos) << ranged.out;
  CommandRun e = Fabatlas("eval lip.yaml --at width=100,lip=3 --json", dir);
  ASSERT_EQ(e.status, 0) << e.err;
  const double ours = nlohmann::json::parse(e.out)["properties"]["volume"].get<double>();
  if (std::system("command -v openscad >/dev/null 2>&1") != 0) GTEST_SKIP() << "openscad not installed";
  const std::string stl = (dir / "peer.stl").string();
  const std::string cmd =
      "cd '" + dir.string() + "' && openscad --quiet -o " + stl + " -D width=100 -D lip=3 organiser.scad 2>/dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const double peer = std::abs(fabatlas::mesh::EnclosedVolume(fabatlas::mesh::ReadMesh(stl)));
  EXPECT_NEAR(ours, peer, 0.01 * peer) << "fabatlas " << ours << " mm^3, OpenSCAD " << peer << " mm^3";

  for (const auto& [args, what] : std::vector<std::pair<std::string, std::string>>{
           {"--expose lip=0:x", "--expose lip=0:x: malformed range '0:x'"},
           {"--expose lip=3:1", "--expose lip=3:1: lo 3 is not below hi 1"},
           {"--expose lip=2:3", "organiser.scad:39: --expose lip: the model's value 1.5 lies outside 2:3"},
           {"--expose nope=0:1", "organiser.scad: --expose nope: the model has no Customizer parameter 'nope'"},
           {"--expose label_text=0:1", "organiser.scad:43: --expose label_text: the parameter is a string"},
           {"--max-dims 0", "organiser.scad: --max-dims 0 is outside 1..16"}}) {
    CommandRun bad = Fabatlas("import-scad organiser.scad --out bad.yaml --voxel 0.5 " + args, dir);
    EXPECT_EQ(bad.status, 2) << args;
    EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
    EXPECT_NE(bad.err.find(what), std::string::npos) << bad.err;
  }
}

// A model without any Customizer annotation, as most published before the
// Customizer (openscad-testing-data's union-coincident-test.scad: two
// crossed bars, one plain number `e`): import-scad exposes nothing and keeps
// the number fixed, the design is one sample, and it evaluates to OpenSCAD
// 2021.01's own render of the model.
TEST(ScadCli, AModelWithoutAnnotationsIsOneSample) {
  const std::filesystem::path model = "/usr/share/openscad/testdata/scad/3D/features/union-coincident-test.scad";
  if (!std::filesystem::exists(model) || std::system("command -v openscad >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "openscad or openscad-testing-data not installed";
  auto dir = fabatlas::testing::FreshTempDir("scad-cli-plain");
  std::filesystem::copy_file(model, dir / "u.scad");
  CommandRun r = Fabatlas("import-scad u.scad --out u.yaml", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("fixed e = 0: no range: a number without a slider annotation"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("(0 exposed: none, one sample; 1 fixed; 0 presets)"), std::string::npos) << r.out;

  CommandRun e = Fabatlas("eval u.yaml --json", dir);
  ASSERT_EQ(e.status, 0) << e.err;
  const auto j = nlohmann::json::parse(e.out);
  EXPECT_TRUE(j["valid"].get<bool>()) << e.out;
  const double ours = j["properties"]["volume"].get<double>();
  const std::string stl = (dir / "peer.stl").string();
  const std::string cmd = "cd '" + dir.string() + "' && openscad --quiet -o " + stl + " u.scad 2>/dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const double peer = std::abs(fabatlas::mesh::EnclosedVolume(fabatlas::mesh::ReadMesh(stl)));
  EXPECT_NEAR(ours, peer, 0.01 * peer) << "fabatlas " << ours << " mm^3, OpenSCAD " << peer << " mm^3";
}

// An include OpenSCAD cannot open is skipped with a warning, and the sample
// says so: openscad-testing-data's misc/include-tests.scad names four files
// that do not exist (one of them from a file it includes); the sample's
// warnings name exactly the files OpenSCAD 2021.01 warns it cannot open.
TEST(ScadCli, SkippedIncludesAreTheSampleWarningsOpenScadGives) {
  const std::filesystem::path model = "/usr/share/openscad/testdata/scad/misc/include-tests.scad";
  if (!std::filesystem::exists(model) || std::system("command -v openscad >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "openscad or openscad-testing-data not installed";
  auto dir = fabatlas::testing::FreshTempDir("scad-cli-include-warnings");
  CommandRun e = Fabatlas("eval '" + model.string() + "' --json", dir);
  ASSERT_EQ(e.status, 0) << e.err;
  const auto j = nlohmann::json::parse(e.out);
  std::set<std::string> ours;
  for (const auto& w : j["warnings"]) {
    const std::string text = w.get<std::string>();
    const auto open = text.find(": include <"), close = text.find(">: not found");
    if (open != std::string::npos && close != std::string::npos) ours.insert(text.substr(open + 11, close - open - 11));
  }
  const std::string log = (dir / "openscad.log").string();
  const std::string cmd = "openscad -o '" + (dir / "peer.stl").string() + "' '" + model.string() + "' 2>'" + log + "'";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::set<std::string> peer;
  std::ifstream in(log);
  const std::string marker = "WARNING: Can't open include file '";
  for (std::string line; std::getline(in, line);)
    if (line.rfind(marker, 0) == 0) peer.insert(line.substr(marker.size(), line.rfind("'") - marker.size()));
  EXPECT_EQ(peer.size(), 4u);
  EXPECT_EQ(ours, peer);
}

}  // namespace
