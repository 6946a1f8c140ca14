// The fabatlas command line as a user runs it: exit codes, one-line errors,
// JSON output.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "../design/design_files.h"

namespace {

struct CommandRun {
  int status = -1;
  std::string out, err;
};

CommandRun Fabatlas(const std::string& args) {
  std::string bin = (fabatlas::testing::BinDir() / "fabatlas").string();
  auto err_path = std::filesystem::temp_directory_path() / ("fabatlas-cli-err-" + std::to_string(::getpid()));
  std::string cmd = bin + " " + args + " 2>" + err_path.string();
  CommandRun r;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) r.out.append(buf.data(), n);
  int status = ::pclose(pipe);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream e(err_path);
  r.err.assign(std::istreambuf_iterator<char>(e), {});
  return r;
}

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
