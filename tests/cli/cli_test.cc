// The fabatlas command line as a user runs it: exit codes, one-line errors,
// JSON output.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "../design/design_files.h"
#include "fabatlas/testing/command_run.h"

namespace {

using fabatlas::testing::CommandRun;
using fabatlas::testing::Fabatlas;

std::string Examples() { return (fabatlas::testing::SourceDir() / "configs/designs").string(); }

int Lines(const std::string& s) { return static_cast<int>(std::count(s.begin(), s.end(), '\n')); }

}  // namespace

TEST(Cli, ValidateExample) {
  CommandRun r = Fabatlas("validate " + Examples() + "/vase.yaml");
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("ok"), std::string::npos);
}

TEST(Cli, ValidateRejectsWithOneLineAndExitTwo) {
  auto path = fabatlas::testing::TempDesign("name: x\nparameters:\n  r: {type: real, min: 2, max: 1}\ntree: {op: sphere, radius: r}\n");
  CommandRun r = Fabatlas("validate " + path.string());
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(path.string() + ":3:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("min > max"), std::string::npos) << r.err;
}

TEST(Cli, EvalJson) {
  CommandRun r = Fabatlas("eval " + Examples() + "/tube_wall_2d.yaml --at radius=10,wall=3 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["valid"].get<bool>());
  EXPECT_TRUE(j["failure"].is_null());
  EXPECT_TRUE(j["checks"]["constraints"]["passed"].get<bool>());
  // Tube: pi (R^2 - r^2) h with R = 10, bore 7, h = 20.
  double expected = M_PI * (100 - 49) * 20;
  EXPECT_NEAR(j["properties"]["volume"].get<double>(), expected, 0.01 * expected);
  EXPECT_TRUE(j["timings"].contains("total"));
}

TEST(Cli, EvalReportsUnsatisfiable) {
  CommandRun r = Fabatlas("eval " + Examples() + "/tube_wall_2d.yaml --at radius=20,wall=2 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j["valid"].get<bool>());
  EXPECT_EQ(j["failure"], "unsat_constraints");
}

TEST(Cli, EvalRejectsBadPoints) {
  for (const char* at : {"radius=nan", "radius=99", "colour=1", "radius"}) {
    CommandRun r = Fabatlas("eval " + Examples() + "/tube_wall_2d.yaml --at " + at);
    EXPECT_EQ(r.status, 2) << at;
    EXPECT_EQ(Lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("--at"), std::string::npos) << r.err;
  }
}

TEST(Cli, EvalWritesMesh) {
  auto out = std::filesystem::temp_directory_path() / ("fabatlas-cli-" + std::to_string(::getpid()) + ".stl");
  CommandRun r = Fabatlas("eval " + Examples() + "/pawn.yaml --mesh " + out.string());
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_GT(std::filesystem::file_size(out), 1000u);
  std::filesystem::remove(out);
}

TEST(Cli, DeltaG) {
  CommandRun r = Fabatlas("dg " + Examples() + "/tube_wall_2d.yaml --a radius=10,wall=3 --b radius=10,wall=3 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NEAR(nlohmann::json::parse(r.out)["dg"].get<double>(), 0.0, 1e-12);
  // Valid against unsatisfiable: dG = 1 by convention.
  r = Fabatlas("dg " + Examples() + "/tube_wall_2d.yaml --a radius=10,wall=3 --b radius=20,wall=2 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_DOUBLE_EQ(nlohmann::json::parse(r.out)["dg"].get<double>(), 1.0);
}

TEST(Cli, MissingDesignAndBadMesh) {
  CommandRun r = Fabatlas("eval /nonexistent/design.yaml");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("/nonexistent/design.yaml"), std::string::npos);
  // A broken mesh (garbage bytes with an .stl name).
  auto dir = fabatlas::testing::TempDesign("", "placeholder").parent_path();
  std::ofstream(dir / "broken.stl") << "solid x\nfacet normal 0 0 nope\n";
  std::ofstream(dir / "d.yaml") << "name: m\nparameters: {s: {type: real, min: 1, max: 2}}\ntree: {op: mesh, file: broken.stl}\n";
  r = Fabatlas("eval " + (dir / "d.yaml").string());
  EXPECT_EQ(r.status, 2) << r.out;
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("broken.stl"), std::string::npos) << r.err;
}

namespace {

// Vertices of a binary STL: their bounding box (min x y z, max x y z).
std::array<double, 6> StlBounds(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  std::array<double, 6> b = {1e300, 1e300, 1e300, -1e300, -1e300, -1e300};
  if (bytes.size() < 84) return b;
  std::uint32_t n = 0;
  std::memcpy(&n, bytes.data() + 80, 4);
  if (bytes.size() < 84 + std::size_t{n} * 50) return b;
  for (std::uint32_t t = 0; t < n; ++t)
    for (int v = 0; v < 3; ++v)
      for (int k = 0; k < 3; ++k) {
        float x = 0;
        std::memcpy(&x, bytes.data() + 84 + t * 50 + 12 + v * 12 + k * 4, 4);
        b[k] = std::min(b[k], double{x});
        b[k + 3] = std::max(b[k + 3], double{x});
      }
  return b;
}

}  // namespace

// `fabatlas prototype` as a user runs it: the solved flap height against
// the analytic one, also after --set; the printable geometry as a closed
// mesh spanning the solved parts; a conflict named with exit status 3; bad
// overrides as one line with exit status 2.
TEST(Cli, PrototypeSolvesFabricatesAndNamesConflicts) {
  // The flap of tests/prototype/data/flap.yaml: solved height gap + 5,
  // deviation |gap + 5 - 30|.
  const auto file = fabatlas::testing::SourceDir() / "tests/prototype/data/flap.yaml";
  CommandRun r = Fabatlas("prototype " + file.string() + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["satisfiable"].get<bool>());
  auto flap = j["cuboids"]["flap"].get<std::vector<double>>();
  ASSERT_EQ(flap.size(), 6u);
  EXPECT_NEAR(flap[5] - flap[4], 35.0, 1e-4);
  EXPECT_NEAR(flap[4], 0.0, 1e-4);
  EXPECT_NEAR(j["deviation_mm"].get<double>(), 5.0, 1e-4);

  r = Fabatlas("prototype " + file.string() + " --set gap=40 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  flap = j["cuboids"]["flap"].get<std::vector<double>>();
  EXPECT_NEAR(flap[5] - flap[4], 45.0, 1e-4);
  EXPECT_NEAR(j["deviation_mm"].get<double>(), 15.0, 1e-4);

  // The printable geometry in the base configuration (docs/prototype.md,
  // Koo et al. Sec. 7): every part's box shrinks by gap/2 = 1 mm on every
  // face, so the flap's top is at 35 - 1 = 34 and the wall's back at
  // -30 + 1 = -29 (the hinge's pin and yokes sit around z = 0, y = 10), to
  // within a voxel (1 mm); three pieces: the plate with its yokes, the flap
  // with its pin, the wall (the hinge's clearance keeps them apart).
  const auto stl = fabatlas::testing::FreshTempDir("prototype") / "flap.stl";
  r = Fabatlas("prototype " + file.string() + " --stl " + stl.string() + " --json");
  ASSERT_EQ(r.status, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["mesh"]["closed"].get<bool>()) << j["mesh"].dump();
  EXPECT_TRUE(j["mesh"]["manifold"].get<bool>()) << j["mesh"].dump();
  EXPECT_FALSE(j["mesh"]["self_intersecting"].get<bool>()) << j["mesh"].dump();
  EXPECT_EQ(j["mesh"]["components"], 3) << j["mesh"].dump();
  const auto b = StlBounds(stl);
  EXPECT_NEAR(b[5], 34.0, 1.0) << "the flap's top";
  EXPECT_NEAR(b[1], -29.0, 1.0) << "the wall's back";

  // A door that must cover a 100 mm opening but be at most 80 mm wide.
  const auto conflict = fabatlas::testing::TempDesign(R"(name: door
parts:
  body: {box: [0, 120, 0, 50, 0, 50], hold: [x0, x1, y0, y1, z0, z1],
         cavities: {opening: {box: [10, 110, 0, 40, 5, 45], open: y0}}}
  door: {box: [10, 110, -3, 0, 5, 45]}
relationships:
  - {type: cover, name: door covers the opening, covering: [door.y1], covered: [body.opening.y0]}
  - {type: geometric, name: narrow door, expression: "door.w <= 80"}
  - {type: geometric, name: wide opening, expression: "body.opening.w >= 100"}
)", "door.yaml");
  r = Fabatlas("prototype " + conflict.string());
  EXPECT_EQ(r.status, 3) << r.err;
  for (const char* name : {"door covers the opening", "narrow door", "wide opening"})
    EXPECT_NE(r.out.find(name), std::string::npos) << name << "\n" << r.out;

  r = Fabatlas("prototype " + file.string() + " --set gap=wide");
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("gap=wide"), std::string::npos) << r.err;
}

// resolve: bad input is one line with exit status 2 (an unknown point, a
// design without transitions, an unknown degree of freedom); the Fig. 15
// hooks are covered in tests/design/design_resolve_test.cc.
TEST(Cli, ResolveRejectsBadInputWithOneLine) {
  const std::string bench = Examples() + "/bench_table.yaml";
  for (const std::string& args : {bench + " --at armrest_height=9000", Examples() + "/vase.yaml",
                                  bench + " --parameters nope", std::string("/nonexistent.yaml")}) {
    CommandRun r = Fabatlas("resolve " + args);
    EXPECT_EQ(r.status, 2) << args << ": " << r.out;
    EXPECT_EQ(Lines(r.err), 1) << args << ": " << r.err;
  }
}

// Precompute's `repairable` class reaches the artifact: the Fig. 15 hooks
// with `repair_with: "lift"`, sampled at the corners of (lift, dx). The
// corners at lift = -5 collide (the prongs overlap by 10 mm) and lifting
// clears them; those at lift = 20 are valid. statistics.json counts the
// failures as repairable, none as collision.
TEST(Cli, SampleRecordsRepairableCollisions) {
  std::ifstream in(fabatlas::testing::SourceDir() / "tests/design/data/hooks_fig15.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string check = "time_steps: 121}";
  ASSERT_NE(text.find(check), std::string::npos);
  text.replace(text.find(check), check.size(), "time_steps: 121, repair_with: \"lift\"}");
  const auto design = fabatlas::testing::TempDesign(text, "hooks.yaml");
  const auto dir = design.parent_path();
  std::ofstream(dir / "job.yaml") << "design: hooks.yaml\nsampling:\n  subdivisions: 1\n  max_depth: 0\n"
                                     "  dg_threshold: 0.2\n  max_samples: 4\nthreads: 2\n";
  CommandRun r = Fabatlas("sample " + (dir / "job.yaml").string() + " --out " + (dir / "out").string());
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream stats(dir / "out" / "statistics.json");
  const auto j = nlohmann::json::parse(stats);
  EXPECT_EQ(j["failure_shares"], (nlohmann::json{{"repairable", 1.0}})) << j.dump();
  EXPECT_NE(r.out.find("repairable"), std::string::npos) << r.out;
}
