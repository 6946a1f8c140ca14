// Objectives and trade-offs on real runs: `fabatlas optimise` and `fabatlas
// inspect --pareto` as processes and /api/optimise, /api/pareto in process
// on the viewer_tube_run fixture (the closed-form tube: valid where wall >=
// 1 + 0.01 radius^2 and radius - wall >= 2; volume pi (r^2 - (r - w)^2) 20;
// PLA 1.24 g/cm^3), and the pawn (configs/designs/pawn.yaml, fixture
// viewer_pawn_run) checked against brute force over its valid samples.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "../cluster/cluster_process.h"
#include "fabatlas/sampling/form.h"
#include "fabatlas/testing/paths.h"
#include "fabatlas/viewer/customiser.h"
#include "fabatlas/viewer/http_api.h"
#include "fabatlas/viewer/optimise.h"
#include "fabatlas/viewer/pareto_front.h"
#include "viewer_runs.h"

namespace fabatlas::viewer {
namespace {

namespace fs = std::filesystem;
using cluster_test::ReadText;
using cluster_test::Spawn;
using cluster_test::WaitExit;
using nlohmann::json;

using viewer_test::TrulyValid;
using viewer_test::TubeVolume;
double WallMin(double r) { return 1 + 0.01 * r * r; }

fs::path ArtifactIn(const fs::path& dir) {
  if (fs::is_directory(dir))
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().extension() == ".fabatlas") return e.path();
  return {};
}

fs::path PawnRunDir() {
  const char* dir = std::getenv("FABATLAS_VIEWER_PAWN_RUN");
  return dir ? fs::path(dir) : testing::BinDir().parent_path() / "test-fixtures" / "viewer-pawn";
}

struct Outcome {
  int status = -1;
  std::string output;
};

Outcome Fabatlas(const std::vector<std::string>& args) {
  static int runs = 0;
  std::vector<std::string> argv = {(testing::BinDir() / "fabatlas").string()};
  argv.insert(argv.end(), args.begin(), args.end());
  const fs::path log = fs::temp_directory_path() /
                       ("fabatlas-optimise-test-" + std::to_string(::getpid()) + "-" + std::to_string(runs++) + ".log");
  const pid_t pid = Spawn(argv, log);
  Outcome r;
  r.status = WaitExit(pid, std::chrono::minutes(2));
  r.output = ReadText(log);
  fs::remove(log);
  return r;
}

TEST(OptimiseCommand, LightestTubeOfRadius15InPla) {
  const Outcome r =
      Fabatlas({"optimise", viewer_test::RunDir().string(), "--min", "weight_PLA", "--hold", "radius=15", "--json"});
  ASSERT_EQ(r.status, 0) << r.output;
  const json j = json::parse(r.output);
  const double radius = j["point"]["radius"], wall = j["point"]["wall"];
  EXPECT_DOUBLE_EQ(radius, 15.0);
  // The lightest valid tube of radius 15 has the wall 1 + 0.01 * 15^2 = 3.25;
  // the form's answer is the first valid sample above it on the wall axis.
  EXPECT_TRUE(TrulyValid(radius, wall));
  EXPECT_GE(wall, WallMin(15));
  EXPECT_LT(wall, WallMin(20) + 11.5 / 5);  // within a bootstrap cell (5 mm of radius, 2.3 mm of wall)
  const double grams = TubeVolume(radius, wall) / 1000 * 1.24;
  EXPECT_NEAR(j["objective"].get<double>(), grams, 1e-2 * grams);  // the sample's meshed volume
  EXPECT_EQ(j["values"].begin().key(), "weight:PLA");
  EXPECT_GE(j["sample"].get<int>(), 0);  // radius 15 is a grid line: a sample, exact
  EXPECT_FALSE(j["interpolated"].get<bool>());

  const Outcome text =
      Fabatlas({"optimise", viewer_test::RunDir().string(), "--min", "weight:PLA", "--hold", "radius=15"});
  ASSERT_EQ(text.status, 0) << text.output;
  EXPECT_NE(text.output.find("minimum of weight:PLA"), std::string::npos) << text.output;
  EXPECT_NE(text.output.find("radius=15"), std::string::npos) << text.output;
}

TEST(OptimiseCommand, BadInputIsOneLineAndExitStatus2) {
  const std::string run = viewer_test::RunDir().string();
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"optimise", run, "--min", "mass"}, "unknown property 'mass'"},
      {{"optimise", run, "--min", "volume", "--hold", "radius=99"}, "outside radius's range"},
      {{"optimise", run, "--min", "volume", "--hold", "radius"}, "expected PARAMETER=VALUE"},
      {{"optimise", run, "--min", "volume", "--hold", "girth=3"}, "no parameter 'girth'"},
      {{"optimise", run, "--weights", "volume=heavy"}, "not a finite number"},
      {{"optimise", run, "--min", "volume", "--max", "volume"}, "exactly one"},
      {{"optimise", run}, "exactly one"},
      {{"optimise", run, "--min", "volume", "--limits", "volume<=1"}, "no valid point"},
      {{"inspect", run, "--pareto", "volume"}, "expected two properties"},
  };
  for (const auto& [args, expected] : cases) {
    const Outcome r = Fabatlas(args);
    EXPECT_EQ(r.status, 2) << args.back() << ": " << r.output;
    EXPECT_NE(r.output.find(expected), std::string::npos) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  }
}

TEST(OptimiseCommand, InspectParetoWritesTheFrontOfVolumeAgainstRadius) {
  const fs::path dir = fs::temp_directory_path() / ("fabatlas-pareto-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const Outcome r =
      Fabatlas({"inspect", viewer_test::RunDir().string(), "--pareto", "volume,max:radius", "--pareto-csv",
                (dir / "front.csv").string(), "--pareto-png", (dir / "front.png").string()});
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(ReadText(dir / "front.png").substr(0, 4), "\x89PNG");
  std::ifstream csv(dir / "front.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "sample,volume,radius,radius,wall");
  // The front of volume (min) against radius (max): the lightest valid tube
  // of each radius, V*(r) = TubeVolume(r, 1 + 0.01 r^2), rising with r. Each
  // row is a truly valid tube no lighter than V* at its radius.
  double last_volume = -1, last_radius = -1;
  int rows = 0;
  while (std::getline(csv, line)) {
    std::vector<double> v;
    std::stringstream in(line);
    for (std::string cell; std::getline(in, cell, ',');) v.push_back(std::stod(cell));
    ASSERT_EQ(v.size(), 5u) << line;
    const double volume = v[1], radius = v[2], wall = v[4];
    EXPECT_DOUBLE_EQ(v[3], radius);
    EXPECT_TRUE(TrulyValid(radius, wall)) << line;
    EXPECT_GE(volume, TubeVolume(radius, WallMin(radius)) * 0.99) << line;  // meshed volumes: within 1 %
    EXPECT_GT(volume, last_volume);
    EXPECT_GT(radius, last_radius);
    last_volume = volume, last_radius = radius;
    ++rows;
  }
  EXPECT_GE(rows, 5);  // at least one per grid line of the radius with a valid sample
  // The widest valid tubes have radius 30 (walls 10 to 12 are valid there).
  EXPECT_DOUBLE_EQ(last_radius, 30.0);
  fs::remove_all(dir);
}

class OptimiseApi : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ASSERT_FALSE(ArtifactIn(viewer_test::RunDir()).empty()) << "run the viewer_tube_run fixture first";
    customiser_ = new Customiser(LoadArtifact(ArtifactIn(viewer_test::RunDir()), CacheChoice::kNone));
  }
  static void TearDownTestSuite() { delete customiser_; }
  static ApiResponse Get(const std::string& path, const std::map<std::string, std::string>& query) {
    return HandleApiRequest(*customiser_, path, query);
  }
  static Customiser* customiser_;
};
Customiser* OptimiseApi::customiser_ = nullptr;

TEST_F(OptimiseApi, GetAndPostAgreeAndBadRequestsAre400) {
  const ApiResponse get = Get("/api/optimise", {{"min", "weight:PLA"}, {"hold", "radius=15"}});
  ASSERT_EQ(get.status, 200) << get.body;
  const ApiResponse post =
      HandleApiPost(*customiser_, "/api/optimise", R"({"min": "weight:PLA", "hold": {"radius": 15}})");
  ASSERT_EQ(post.status, 200) << post.body;
  EXPECT_EQ(get.body, post.body);
  const json j = json::parse(get.body);
  EXPECT_TRUE(j["found"].get<bool>());
  EXPECT_TRUE(j["valid"].get<bool>());
  EXPECT_DOUBLE_EQ(j["u"][0].get<double>(), 15.0);
  EXPECT_TRUE(TrulyValid(15.0, j["u"][1].get<double>()));

  // Under a limit: the widest tube with volume <= 9000 mm^3.
  const json limited = json::parse(Get("/api/optimise", {{"max", "radius"}, {"limits", "volume<=9000"}}).body);
  ASSERT_TRUE(limited["found"].get<bool>());
  const auto& props = customiser_->form().samples.at(limited["sample"].get<std::size_t>()).outcome.properties;
  EXPECT_LE(props.at("volume"), 9000.0);
  // The bound: the lightest tube of radius r weighs V*(r) = TubeVolume(r, 1 + 0.01 r^2).
  EXPECT_LE(TubeVolume(limited["u"][0].get<double>(), WallMin(limited["u"][0].get<double>())), 9000.0 * 1.01);

  for (const auto& query : std::vector<std::map<std::string, std::string>>{{{"min", "nosuch"}},
                                                                           {},
                                                                           {{"min", "volume"}, {"max", "volume"}},
                                                                           {{"min", "volume"}, {"hold", "radius=99"}},
                                                                           {{"weights", "volume=x"}}}) {
    const ApiResponse r = Get("/api/optimise", query);
    EXPECT_EQ(r.status, 400) << r.body;
    EXPECT_EQ(std::count(r.body.begin(), r.body.end(), '\n'), 1) << r.body;
  }
  EXPECT_EQ(HandleApiPost(*customiser_, "/api/optimise", "[1]").status, 400);
  EXPECT_EQ(HandleApiPost(*customiser_, "/api/optimise", "{\"min\": true}").status, 400);
  EXPECT_EQ(HandleApiPost(*customiser_, "/api/optimise", "not json").status, 400);
  EXPECT_EQ(HandleApiPost(*customiser_, "/api/intervals", "{}").status, 405);
  EXPECT_EQ(Get("/api/pareto", {}).status, 400);
  EXPECT_EQ(Get("/api/pareto", {{"axes", "volume,nosuch"}}).status, 400);
}

TEST_F(OptimiseApi, ParetoAnswerIsTheFrontOfTheValidSamples) {
  const ApiResponse r = Get("/api/pareto", {{"axes", "volume,max:radius"}, {"dominated", "50"}});
  ASSERT_EQ(r.status, 200) << r.body;
  const json j = json::parse(r.body);
  EXPECT_EQ(j["a"], "volume");
  EXPECT_EQ(j["b"], "radius");
  EXPECT_LE(j["dominated"].size(), 50u);
  // Brute force: no valid sample is at most as heavy and at least as wide.
  const auto& samples = customiser_->form().samples;
  for (const auto& p : j["points"]) {
    const double v = p["a"], r0 = p["b"];
    EXPECT_TRUE(TrulyValid(p["u"][0], p["u"][1]));
    for (const auto& s : samples)
      if (s.outcome.valid) {
        EXPECT_FALSE(s.outcome.properties.at("volume") <= v && s.u[0] >= r0 &&
                     (s.outcome.properties.at("volume") < v || s.u[0] > r0))
            << p.dump();
      }
  }
}

// The pawn: every answer equals brute force over the valid samples.
class Pawn : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ASSERT_FALSE(ArtifactIn(PawnRunDir()).empty()) << "run the viewer_pawn_run fixture first";
    customiser_ = new Customiser(LoadArtifact(ArtifactIn(PawnRunDir()), CacheChoice::kNone));
  }
  static void TearDownTestSuite() { delete customiser_; }
  static Customiser* customiser_;
};
Customiser* Pawn::customiser_ = nullptr;

TEST_F(Pawn, OptimaAndFrontEqualBruteForceOverValidSamples) {
  const Customiser& c = *customiser_;
  const auto& samples = c.form().samples;
  const auto& pla = c.source().materials.at(0);
  ASSERT_EQ(pla.name, "PLA");
  // Brute force, with this test's own arithmetic for weight.
  double lightest = std::numeric_limits<double>::infinity(), tallest_bbox = -lightest;
  std::int64_t lightest_id = -1;
  int valid = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (!samples[i].outcome.valid) continue;
    ++valid;
    const double grams = samples[i].outcome.properties.at("volume") / 1000 * pla.density_g_per_cm3;
    if (grams < lightest) lightest = grams, lightest_id = static_cast<std::int64_t>(i);
    tallest_bbox = std::max(tallest_bbox, samples[i].outcome.properties.at("bbox_z"));
  }
  ASSERT_GT(valid, 10);
  OptimiseOptions o;
  o.terms = ParseObjective("weight_PLA");
  const OptimiseResult r = Optimise(c.form(), c.corners(), c.source().materials, o);
  ASSERT_TRUE(r.found);
  EXPECT_DOUBLE_EQ(r.objective, lightest);
  EXPECT_EQ(r.sample, lightest_id);
  EXPECT_EQ(r.candidates, valid);
  o.terms = ParseObjective("bbox_z");
  o.maximise = true;
  EXPECT_DOUBLE_EQ(Optimise(c.form(), c.corners(), c.source().materials, o).objective, tallest_bbox);

  // Held at height 45 (the issue's example): the answer lies on the slice,
  // in the valid region, its weight interpolated along the height between
  // its corners exactly as this test computes it, and no valid point of a
  // dense scan of the slice through all-valid leaves is lighter.
  o.terms = ParseObjective("weight_PLA");
  o.maximise = false;
  o.hold = ParseHolds("height=45", c.space());
  const OptimiseResult held = Optimise(c.form(), c.corners(), c.source().materials, o);
  ASSERT_TRUE(held.found);
  EXPECT_DOUBLE_EQ(held.u[1], 45.0);
  EXPECT_TRUE(c.IsValid(held.u));
  const auto grams = [&](std::int64_t id) {
    return samples[id].outcome.properties.at("volume") / 1000 * pla.density_g_per_cm3;
  };
  if (held.sample >= 0) {
    EXPECT_DOUBLE_EQ(held.objective, grams(held.sample));
  } else {
    ASSERT_EQ(held.corners.size(), 2u);
    const auto &lo = samples[held.corners[0]], &hi = samples[held.corners[1]];
    EXPECT_EQ(lo.u[0], held.u[0]);
    EXPECT_EQ(hi.u[0], held.u[0]);
    const double t = (45.0 - lo.u[1]) / (hi.u[1] - lo.u[1]);
    EXPECT_NEAR(held.objective, (1 - t) * grams(held.corners[0]) + t * grams(held.corners[1]), 1e-9 * held.objective);
  }
  const sampling::DesignSpace space = c.form().space();
  for (int k = 0; k <= 2000; ++k) {
    const std::vector<double> u = {5.0 + 7.0 * k / 2000, 45.0};
    const auto leaf = sampling::LocateLeaf(c.form(), space, u);
    ASSERT_TRUE(leaf);
    const auto& node = c.form().trees[leaf->tree].nodes[leaf->node];
    if (!sampling::IsAllValidLeaf(c.form(), node)) continue;
    const auto ids = sampling::CornerSampleIds(c.form(), node);
    const double x0 = space.value(0, node.lo[0]), x1 = space.value(0, node.hi[0]);
    const double y0 = space.value(1, node.lo[1]), y1 = space.value(1, node.hi[1]);
    const double s = (u[0] - x0) / (x1 - x0), t = (u[1] - y0) / (y1 - y0);
    const double w = (1 - s) * (1 - t) * grams(ids[0]) + s * (1 - t) * grams(ids[1]) + (1 - s) * t * grams(ids[2]) +
                     s * t * grams(ids[3]);
    EXPECT_GE(w, held.objective - 1e-9) << "head " << u[0];
  }

  // The front of weight (min) against head (max) equals brute force.
  const ParetoFront front = ParetoFrontOf(c.form(), c.source().materials, ParseParetoAxes("weight:PLA,max:head"));
  std::set<std::int64_t> brute;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (!samples[i].outcome.valid) continue;
    bool dominated = false;
    for (std::size_t k = 0; k < samples.size() && !dominated; ++k) {
      if (!samples[k].outcome.valid) continue;
      const double gi = grams(static_cast<std::int64_t>(i)), gk = grams(static_cast<std::int64_t>(k));
      const double hi = samples[i].u[0], hk = samples[k].u[0];
      dominated = gk <= gi && hk >= hi && (gk < gi || hk > hi);
    }
    if (!dominated) brute.insert(static_cast<std::int64_t>(i));
  }
  std::set<std::int64_t> got;
  for (const auto& p : front.points) got.insert(p.sample);
  EXPECT_EQ(got, brute);
}

}  // namespace
}  // namespace fabatlas::viewer
