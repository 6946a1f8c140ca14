// The customiser's API in process (HandleApiRequest on the artifact of the
// viewer_tube_run fixture): reasons in words, runtime limits on properties
// against the tube's closed form (valid where wall >= 1 + 0.01 radius^2 and
// radius - wall >= 2; volume pi (r^2 - (r - w)^2) 20), and faults answered
// as a 500 with their reason.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <sstream>

#include <nlohmann/json.hpp>

#include "corner_table_check.h"
#include "fabatlas/artifact/glb.h"
#include "fabatlas/mesh/mesh_report.h"
#include "fabatlas/testing/paths.h"
#include "fabatlas/viewer/customiser.h"
#include "fabatlas/viewer/http_api.h"
#include "viewer_runs.h"

namespace fabatlas::viewer {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

fs::path Artifact() {
  for (const auto& e : fs::directory_iterator(viewer_test::RunDir()))
    if (e.path().extension() == ".fabatlas") return e.path();
  return {};
}

using viewer_test::TubeVolume;

class Api : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ASSERT_FALSE(Artifact().empty()) << "run the viewer_tube_run fixture first";
    customiser_ = new Customiser(LoadArtifact(Artifact()));
  }
  static void TearDownTestSuite() { delete customiser_; }
  static json Get(const std::string& path, const std::map<std::string, std::string>& query, int status = 200) {
    const ApiResponse r = HandleApiRequest(*customiser_, path, query);
    EXPECT_EQ(r.status, status) << path << ": " << r.body;
    return r.status == 200 ? json::parse(r.bytes()) : json(r.body);
  }
  static Customiser* customiser_;
};
Customiser* Api::customiser_ = nullptr;

// The corner table serve builds at load against the search of
// Form::sample_ids it replaces, on this real run's artifact.
TEST_F(Api, CornerTableGivesTheAnswersOfTheSampleIdSearch) {
  ExpectCornerTableMatchesSampleIdSearch(customiser_->form(), customiser_->corners(), 2000);
}

TEST_F(Api, ReasonNamesTheViolatedConstraintInTheDesignsWords) {
  // (29, 1) breaks wall >= 1 + 0.01 radius^2 (the other constraint holds).
  const json r = Get("/api/reason", {{"u", "29,1"}});
  EXPECT_EQ(r["check"], "constraints");
  EXPECT_EQ(r["failure"], "unsat_constraints");
  EXPECT_NE(r["reason"].get<std::string>().find("wall >= 1 + 0.01 * radius^2"), std::string::npos) << r.dump();
  // The sample explained is truly invalid and lies next to the point.
  const double radius = r["sample_u"][0], wall = r["sample_u"][1];
  EXPECT_LT(wall, 1 + 0.01 * radius * radius);
  EXPECT_LT(std::abs(radius - 29) + std::abs(wall - 1), 5.0);
  // (8, 7.5) breaks radius - wall >= 2 only: a different constraint named.
  const json b = Get("/api/reason", {{"u", "8,7.5"}});
  EXPECT_NE(b["reason"].get<std::string>().find("bore"), std::string::npos) << b.dump();
}

TEST_F(Api, AVolumeLimitShrinksTheWallStretchToTheClosedFormBound) {
  // At radius 15 the valid walls are [3.25, 12]; volume <= V caps the wall
  // at w* with pi (2 r w* - w*^2) 20 = V. The run's samples on that line
  // (tube_wall_2d.yaml: 5 subdivisions of [0.5, 12]) are at walls 0.5 +
  // 2.3 k (and 3.95 where the sampler split): w* = 8.5 lies between 7.4,
  // within the limit, and 9.7, beyond it, both far above the smallest valid
  // wall, so the stretch must end in [7.4, w*].
  const double r = 15, v = TubeVolume(15, 8.5);
  const double w_star = r - std::sqrt(r * r - v / (20 * std::numbers::pi));  // = 8.5
  const double last_sample_within = 0.5 + 3 * 2.3;                           // 7.4
  const auto valid_hi = [&](const json& j) {
    double hi = -1;
    for (const auto& s : j["dimensions"][1])
      if (s["valid"].get<bool>() && s["lo"].get<double>() <= 5 && s["hi"].get<double>() >= 5) hi = s["hi"];
    return hi;
  };
  const json free = Get("/api/intervals", {{"u", "15,5"}});
  const json limited = Get("/api/intervals", {{"u", "15,5"}, {"limits", "volume<=" + std::to_string(v)}});
  const double free_hi = valid_hi(free), limited_hi = valid_hi(limited);
  EXPECT_GE(free_hi, 11.0);
  // Conservative: ends where a sample meets the limit, the sampled volume
  // within 2% of the closed form (0.5 mm voxels), so below w* plus that.
  EXPECT_LE(limited_hi, w_star + 0.3);
  EXPECT_GE(limited_hi, last_sample_within - 1e-9);
  // The stretch beyond says why, in words.
  json beyond;
  for (const auto& s : limited["dimensions"][1])
    if (!s["valid"].get<bool>() && s["lo"].get<double>() >= limited_hi - 1e-9) beyond = s;
  ASSERT_FALSE(beyond.is_null()) << limited.dump();
  EXPECT_EQ(beyond["failures"], json::array({"limit:volume"}));
  const json why =
      Get("/api/reason", {{"u", "15," + std::to_string(limited_hi + 1)}, {"limits", "volume<=" + std::to_string(v)}});
  EXPECT_EQ(why["check"], "limits");
  EXPECT_NE(why["reason"].get<std::string>().find("above your limit"), std::string::npos) << why.dump();
  // Snapping and properties keep to the limit.
  const json p = Get("/api/properties", {{"u", "15,11"}, {"limits", "volume<=" + std::to_string(v)}});
  EXPECT_LE(p["properties"]["volume"].get<double>(), v);
  // A weight limit is the same bound through the density (PLA 1.24 g/cm^3).
  const json w = Get("/api/intervals", {{"u", "15,5"}, {"limits", "weight:PLA<=" + std::to_string(v / 1000 * 1.24)}});
  EXPECT_NEAR(valid_hi(w), limited_hi, 1e-9);
}

TEST_F(Api, BadLimitsAre400WithOneLine) {
  for (const std::string bad : {"volume", "volume<=abc", "weight:gold<=3", "volume<=nan", "<=3"}) {
    const ApiResponse r = HandleApiRequest(*customiser_, "/api/intervals", {{"u", "15,6"}, {"limits", bad}});
    EXPECT_EQ(r.status, 400) << bad;
    EXPECT_EQ(r.body.find('\n'), r.body.size() - 1) << bad << ": " << r.body;
  }
}

TEST(ApiFaults, AnInternalFaultIsA500WithItsReason) {
  // A source naming a starting point the form does not have: /api/form
  // fails inside (std::out_of_range), which must not escape as a dropped
  // connection.
  CustomiserSource source = LoadArtifact(Artifact());
  source.starting_points = {1000000};
  const Customiser c(std::move(source));
  const ApiResponse r = HandleApiRequest(c, "/api/form", {});
  EXPECT_EQ(r.status, 500);
  EXPECT_EQ(r.body.rfind("internal error: ", 0), 0u) << r.body;
  EXPECT_EQ(r.body.find('\n'), r.body.size() - 1) << r.body;
}

TEST_F(Api, StateGraphOfADesignWithoutOneIsABadRequest) {
  // The tube has no objects or transitions: one line, 400 (the bench's state
  // graph is played in viewer_browser_transition_test).
  const json r = Get("/api/state_graph", {{"u", "15,6"}}, 400);
  EXPECT_EQ(r.get<std::string>(), "this design has no state graph (objects and transitions)\n");
  const json form = Get("/api/form", {});
  EXPECT_TRUE(form["transitions"].empty() && form["objects"].empty() && form["states"].empty()) << form.dump();
}

// The peg rail run (viewer_peg_run): valid at length 17.5 by interpolation
// between its valid samples at 15 and 20, but its 20 mm bulge there breaks
// max_volume (17.5 x 6 x 22 mm^3 > 1000): the export answers 400 with the
// failing check, the same line as `fabatlas export`.
TEST(ApiExport, ChecksRunAtExactlyThePointBeforeWriting) {
  const fs::path run = viewer_test::PegRunDir();
  ASSERT_TRUE(fs::exists(run / "peg_rail.fabatlas")) << "run the viewer_peg_run fixture first: " << run;
  const Customiser c(LoadArtifact(run / "peg_rail.fabatlas"));
  const ApiResponse at = HandleApiRequest(c, "/api/intervals", {{"u", "17.5,1,0"}});
  ASSERT_EQ(at.status, 200) << at.body;
  EXPECT_TRUE(json::parse(at.bytes())["valid"].get<bool>());
  const ApiResponse r = HandleApiRequest(c, "/api/export", {{"u", "17.5,1,0"}, {"format", "stl"}});
  EXPECT_EQ(r.status, 400);
  EXPECT_EQ(std::count(r.body.begin(), r.body.end(), '\n'), 1) << r.body;
  EXPECT_EQ(
      r.body.rfind("length=17.5,pegs=1,peg=thin fails check 'max_volume' at exactly this point (too_much_material: "
                   "material volume ",
                   0),
      0u)
      << r.body;
  const ApiResponse ok = HandleApiRequest(c, "/api/export", {{"u", "16,1,0"}, {"format", "stl"}});
  EXPECT_EQ(ok.status, 200) << ok.body;
  EXPECT_EQ(ok.headers.at("X-Checks"), "constraints,geometry,max_volume");
}

// Exact previews (issue 35): between samples, with a budget nothing on this
// host can exceed, the preview is the design at exactly u — the tube's
// analytic volume there, not the snapped sample's — and says so; a budget
// of 0 always snaps.
double GlbVolume(const std::string& glb) {
  mesh::InspectOptions inspect;
  inspect.check_self_intersection = false;
  return mesh::InspectMesh(artifact::GlbToMesh(glb), inspect).volume;
}

std::vector<double> PointOf(const std::string& text) {
  std::vector<double> u;
  std::istringstream in(text);
  for (std::string item; std::getline(in, item, ',');) u.push_back(std::stod(item));
  return u;
}

TEST(ApiExactPreview, BetweenSamplesShowsTheDesignAtExactlyThePoint) {
  ASSERT_FALSE(Artifact().empty()) << "run the viewer_tube_run fixture first";
  const Customiser c(LoadArtifact(Artifact()), {}, ExactPreviewOptions{.budget_seconds = 600});
  // The run has no sample with a wall between 7.4 and 9.7 mm.
  const std::map<std::string, std::string> at = {{"u", "20.6,8.55"}};
  auto with_exact = at;
  with_exact["exact"] = "1";
  const ApiResponse snapped = HandleApiRequest(c, "/api/preview.glb", at);
  const ApiResponse exact = HandleApiRequest(c, "/api/preview.glb", with_exact);
  ASSERT_EQ(snapped.status, 200) << snapped.body;
  ASSERT_EQ(exact.status, 200) << exact.body;
  EXPECT_EQ(snapped.headers.at("X-Preview"), "snapped");
  EXPECT_EQ(snapped.headers.count("X-Preview-Fallback"), 0u);
  EXPECT_EQ(exact.headers.at("X-Preview"), "exact");
  EXPECT_EQ(exact.headers.at("X-Sample"), snapped.headers.at("X-Sample"));
  EXPECT_EQ(PointOf(exact.headers.at("X-Preview-U")), (std::vector<double>{20.6, 8.55}));
  const std::vector<double> s = PointOf(snapped.headers.at("X-Preview-U"));
  ASSERT_EQ(s.size(), 2u);
  EXPECT_NE(s, (std::vector<double>{20.6, 8.55})) << "the point must lie between samples";
  EXPECT_GT(std::stod(exact.headers.at("X-Preview-Seconds")), 0.0);

  const double want = TubeVolume(20.6, 8.55);
  const double other = TubeVolume(s[0], s[1]);
  ASSERT_GT(std::abs(other - want), 0.05 * want) << "the snapped sample must be told apart at 2%";
  EXPECT_NE(exact.bytes(), snapped.bytes());
  EXPECT_NEAR(GlbVolume(exact.bytes()), want, 0.02 * want);
  EXPECT_NEAR(GlbVolume(snapped.bytes()), other, 0.02 * other);
}

TEST(ApiExactPreview, ABudgetOfZeroAlwaysSnaps) {
  ASSERT_FALSE(Artifact().empty()) << "run the viewer_tube_run fixture first";
  const Customiser c(LoadArtifact(Artifact()), {}, ExactPreviewOptions{.budget_seconds = 0});
  for (const char* u : {"20.6,8.55", "12.2,5.1", "25,11"}) {
    const ApiResponse r = HandleApiRequest(c, "/api/preview.glb", {{"u", u}, {"exact", "1"}});
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(r.headers.at("X-Preview"), "snapped") << u;
    EXPECT_EQ(r.headers.at("X-Preview-Fallback"), "budget") << u;
    const ApiResponse plain = HandleApiRequest(c, "/api/preview.glb", {{"u", u}});
    EXPECT_EQ(r.bytes(), plain.bytes()) << u;
  }
}

TEST(ApiExactPreview, OutsideTheValidRegionSnapsAndBadFlagsAre400) {
  ASSERT_FALSE(Artifact().empty()) << "run the viewer_tube_run fixture first";
  const Customiser c(LoadArtifact(Artifact()), {}, ExactPreviewOptions{.budget_seconds = 600});
  // wall 2 < 1 + 0.01 * 25^2: outside the closed-form region.
  const ApiResponse r = HandleApiRequest(c, "/api/preview.glb", {{"u", "25,2"}, {"exact", "1"}});
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(r.headers.at("X-Preview"), "snapped");
  EXPECT_EQ(r.headers.at("X-Preview-Fallback"), "outside");
  const ApiResponse bad = HandleApiRequest(c, "/api/preview.glb", {{"u", "20.6,8.55"}, {"exact", "yes"}});
  EXPECT_EQ(bad.status, 400);
  EXPECT_EQ(bad.body, "exact must be 0 or 1, got 'yes'\n");
}

// The estimate: the snapped preview's time times the median ratio of the
// last ExactPreviewCost::kWindow exact previews (1 before any).
TEST(ExactPreviewCost, IsTheSnappedTimeTimesTheMedianRecentRatio) {
  ExactPreviewCost cost;
  EXPECT_EQ(cost.Estimate(0.04), 0.04);
  cost.Record(0.01, 0.02);  // 2
  cost.Record(0.01, 0.50);  // 50
  cost.Record(0.02, 0.06);  // 3
  EXPECT_DOUBLE_EQ(cost.Estimate(0.1), 0.3);
  for (int i = 0; i < ExactPreviewCost::kWindow; ++i) cost.Record(0.1, 0.1);  // the old ratios leave the window
  EXPECT_DOUBLE_EQ(cost.Estimate(0.1), 0.1);
  cost.Record(0, 1);  // ignored
  EXPECT_DOUBLE_EQ(cost.Estimate(0.1), 0.1);
}

}  // namespace
}  // namespace fabatlas::viewer
