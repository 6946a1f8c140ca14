// The viewer's runtime lookups (Fab Forms Sec. 7.2-7.4) on forms sampled from
// analytic designs, so every expected interval, snap and starting point
// follows from the designs' closed-form validity and ΔG.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "../sampling/analytic_designs.h"
#include "corner_table_check.h"
#include "fabatlas/cache/starting_points.h"
#include "fabatlas/error.h"
#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sampling/executor.h"
#include "fabatlas/artifact/artifact.h"
#include "fabatlas/testing/paths.h"
#include "fabatlas/viewer/customiser.h"
#include "fabatlas/viewer/leaf_corners.h"
#include "fabatlas/viewer/snap.h"
#include "fabatlas/viewer/valid_region.h"

namespace fabatlas::viewer {
namespace {

using sampling::Dimension;
using sampling::DimensionKind;
using sampling::SampleOutcome;
using sampling::SamplePoint;

std::vector<Dimension> UnitSquare() {
  return {{"x", DimensionKind::kReal, 0.0, 1.0, {}}, {"y", DimensionKind::kReal, 0.0, 1.0, {}}};
}

sampling::Form Sample(sampling::SampleEvaluator& evaluator, std::vector<Dimension> dims, int subdivisions,
                      int max_depth) {
  sampling::DesignSpace space(std::move(dims), subdivisions);
  sampling::ThreadPoolExecutor executor(1);
  sampling::SamplingOptions options;
  options.max_depth = max_depth;
  options.dg_threshold = 0.1;
  return sampling::SampleDesignSpace(space, evaluator, executor, options).form;
}

// A thin valid band 0.35 <= y <= 0.45: below it "too_thin", above "too_thick".
// On the 5x5 bootstrap grid (lines every 0.2) no cell is all-valid, but the
// grid line y = 0.4 is: valid only through the face rule of Sec. 7.2.
class Band : public sampling::SampleEvaluator {
 public:
  SampleOutcome EvaluateSample(const SamplePoint& p) override {
    SampleOutcome o;
    if (p.u[1] < 0.35)
      o.failure_type = "too_thin";
    else if (p.u[1] > 0.45)
      o.failure_type = "too_thick";
    o.valid = o.failure_type.empty();
    return o;
  }
  double GeometryChange(const SamplePoint&, const SamplePoint&) override { return 0.0; }
};

// Valid where x <= 0.3 or x >= 0.7 ("gap" between): two components.
class Gap : public sampling::SampleEvaluator {
 public:
  SampleOutcome EvaluateSample(const SamplePoint& p) override {
    SampleOutcome o;
    o.valid = p.u[0] <= 0.3 || p.u[0] >= 0.7;
    if (!o.valid) o.failure_type = "gap";
    return o;
  }
  double GeometryChange(const SamplePoint&, const SamplePoint&) override { return 0.0; }
};

// The corner table against the search of Form::sample_ids it replaces, on a
// real artifact: the tube_wall_2d job as `fabatlas run` published it (schema
// version 1; viewer_api_test does the same on the viewer_tube_run fixture).
TEST(ViewerLeafCorners, TableGivesTheAnswersOfTheSampleIdSearchOnARealArtifact) {
  const artifact::Artifact art =
      artifact::ReadArtifact(testing::SourceDir() / "tests/data/artifact_v1/tube_wall_2d.fabatlas");
  const LeafCorners corners(art.form);
  ExpectCornerTableMatchesSampleIdSearch(art.form, corners, 2000);

  // A copy with other validity (as ApplyLimits makes) fits; a form with
  // other trees does not, and the lookups refuse it.
  sampling::Form other = art.form;
  other.samples[0].outcome.valid = !other.samples[0].outcome.valid;
  EXPECT_TRUE(corners.Fits(other));
  other.trees.pop_back();
  EXPECT_FALSE(corners.Fits(other));
  EXPECT_THROW(IsValidPoint(other, other.space(), corners, {15, 5}), std::invalid_argument);
}

TEST(ViewerValidRegion, FaceRuleMakesAnAllValidGridLineValid) {
  Band band;
  const sampling::Form form = Sample(band, UnitSquare(), 5, 0);
  const sampling::DesignSpace space = form.space();
  const LeafCorners corners(form);
  EXPECT_TRUE(IsValidPoint(form, space, corners, {0.3, 0.4}));    // on the all-valid face
  EXPECT_TRUE(IsValidPoint(form, space, corners, {0.4, 0.4}));    // on an all-valid vertex
  EXPECT_FALSE(IsValidPoint(form, space, corners, {0.3, 0.41}));  // inside a cell with invalid corners
  EXPECT_FALSE(IsValidPoint(form, space, corners, {0.3, 0.2}));
  EXPECT_FALSE(IsValidPoint(form, space, corners, {0.3, 1.5}));  // outside the space
  EXPECT_FALSE(IsValidPoint(form, space, corners, {0.3}));       // wrong arity

  // Along x through y = 0.4: the whole line is one valid interval.
  const auto along_x = LineStretches(form, space, corners, {0.3, 0.4}, 0);
  ASSERT_EQ(along_x.size(), 1u);
  EXPECT_TRUE(along_x[0].valid);
  EXPECT_DOUBLE_EQ(along_x[0].lo, 0.0);
  EXPECT_DOUBLE_EQ(along_x[0].hi, 1.0);

  // Along y through x = 0.3: the single point y = 0.4, invalid on both sides
  // for the reasons recorded below and above the band.
  const auto along_y = LineStretches(form, space, corners, {0.3, 0.4}, 1);
  ASSERT_EQ(along_y.size(), 3u);
  EXPECT_FALSE(along_y[0].valid);
  EXPECT_DOUBLE_EQ(along_y[0].lo, 0.0);
  EXPECT_DOUBLE_EQ(along_y[0].hi, 0.4);
  EXPECT_EQ(along_y[0].failures, std::vector<std::string>{"too_thin"});
  EXPECT_TRUE(along_y[1].valid);
  EXPECT_DOUBLE_EQ(along_y[1].lo, 0.4);
  EXPECT_DOUBLE_EQ(along_y[1].hi, 0.4);
  EXPECT_FALSE(along_y[2].valid);
  EXPECT_DOUBLE_EQ(along_y[2].lo, 0.4);
  EXPECT_DOUBLE_EQ(along_y[2].hi, 1.0);
  EXPECT_EQ(along_y[2].failures, std::vector<std::string>{"too_thick"});
  EXPECT_EQ(FailuresAt(form, space, corners, {0.3, 0.9}), std::vector<std::string>{"too_thick"});
  EXPECT_TRUE(FailuresAt(form, space, corners, {0.3, 0.4}).empty());
}

TEST(ViewerValidRegion, NonConvexLineHasTwoIntervalsAtTheRefinedBoundaries) {
  // Subdivision refines the cells cut by x = 0.3 and x = 0.7 (ΔG(valid,
  // invalid) = 1) down to width 0.2 / 2^3; 0.3 and 0.7 are cut midpoints, so
  // the estimated intervals are exactly [0, 0.3] and [0.7, 1].
  Gap gap;
  const sampling::Form form = Sample(gap, UnitSquare(), 5, 3);
  const sampling::DesignSpace space = form.space();
  const LeafCorners corners(form);
  for (double y : {0.0, 0.13, 0.4, 1.0}) {
    const auto valid = ValidIntervals(form, space, corners, {0.1, y}, 0);
    ASSERT_EQ(valid.size(), 2u) << "y = " << y;
    EXPECT_DOUBLE_EQ(valid[0].lo, 0.0);
    EXPECT_DOUBLE_EQ(valid[0].hi, 0.3);
    EXPECT_DOUBLE_EQ(valid[1].lo, 0.7);
    EXPECT_DOUBLE_EQ(valid[1].hi, 1.0);
    const auto all = LineStretches(form, space, corners, {0.1, y}, 0);
    ASSERT_EQ(all.size(), 3u);
    EXPECT_FALSE(all[1].valid);
    EXPECT_EQ(all[1].failures, std::vector<std::string>{"gap"});
  }
  // Interval ends passed back are valid points; the middle of the gap is not.
  EXPECT_TRUE(IsValidPoint(form, space, corners, {0.3, 0.5}));
  EXPECT_TRUE(IsValidPoint(form, space, corners, {space.value(0, space.key_lo(0)) + 0.7, 0.5}));
  EXPECT_FALSE(IsValidPoint(form, space, corners, {0.31, 0.5}));
  // Along y every line is entirely valid or entirely invalid.
  EXPECT_EQ(ValidIntervals(form, space, corners, {0.2, 0.5}, 1).size(), 1u);
  EXPECT_TRUE(ValidIntervals(form, space, corners, {0.5, 0.5}, 1).empty());
  EXPECT_THROW(LineStretches(form, space, corners, {0.5, 1.5}, 1), InputError);
  EXPECT_THROW(LineStretches(form, space, corners, {0.5, 0.5}, 2), InputError);
}

TEST(ViewerValidRegion, IntervalsMatchTheAnalyticRegionOfTheHollowCylinder) {
  // Valid iff wall >= t(R) = 0.5 + 0.01 R^2: along the wall axis at R the true
  // interval is [t(R), 5]. The estimate is conservative (lo >= t(R)), lo is
  // a cut with an invalid leaf just below it, and that leaf lies inside one
  // bootstrap cell (3 mm of R, 0.9 mm of wall), so lo < t(R + 3) + 0.9.
  sampling::testing::HollowCylinder2D cylinder;
  const sampling::Form form = Sample(cylinder, cylinder.Dimensions(), 5, 4);
  const sampling::DesignSpace space = form.space();
  const LeafCorners corners(form);
  for (double R : {6.0, 10.0, 13.7, 18.0}) {
    const auto valid = ValidIntervals(form, space, corners, {R, 2.0}, 1);
    ASSERT_EQ(valid.size(), 1u) << "R = " << R;
    const auto t = [](double r) { return 0.5 + 0.01 * r * r; };
    EXPECT_GE(valid[0].lo, t(R) - 1e-9);
    EXPECT_LT(valid[0].lo, t(R + 3.0) + 0.9);
    EXPECT_DOUBLE_EQ(valid[0].hi, 5.0);
    EXPECT_TRUE(IsValidPoint(form, space, corners, {R, valid[0].lo}));
    EXPECT_FALSE(IsValidPoint(form, space, corners, {R, valid[0].lo - 1e-6}));
    EXPECT_TRUE(cylinder.TrulyValid({R, valid[0].lo}));
  }
}

// One leaf over [0,1]^2 (a single bootstrap cell, no splits) with ΔG 0.9 on
// the bottom edge, 0.1 on the top edge and 0.5 on both vertical edges.
class Skewed : public sampling::SampleEvaluator {
 public:
  explicit Skewed(bool top_left_valid) : top_left_valid_(top_left_valid) {}
  SampleOutcome EvaluateSample(const SamplePoint& p) override {
    SampleOutcome o;
    o.valid = top_left_valid_ || !(p.u[0] == 0 && p.u[1] == 1);
    if (!o.valid) o.failure_type = "hole";
    return o;
  }
  double GeometryChange(const SamplePoint& a, const SamplePoint& b) override {
    if (a.u[1] == b.u[1]) return a.u[1] == 0 ? 0.9 : 0.1;
    return 0.5;
  }

 private:
  bool top_left_valid_;
};

std::vector<double> SampleU(const sampling::Form& form, const std::optional<Snap>& snap) {
  return snap ? form.samples[snap->sample].u : std::vector<double>{};
}

TEST(ViewerSnap, ClosestCornerByDeltaGWeightedDistanceNotByPosition) {
  // At t = (0.4, 0.4): D to (0,0) = 0.4*0.9 + 0.4*0.5 = 0.56, to (1,0) = 0.74,
  // to (0,1) = 0.4*0.1 + 0.6*0.5 = 0.34, to (1,1) = 0.36. Nearest by
  // position would be (0,0).
  Skewed skewed(true);
  const sampling::Form form = Sample(skewed, UnitSquare(), 1, 0);
  const auto snap = SnapToValidSample(form, form.space(), {0.4, 0.4});
  ASSERT_TRUE(snap);
  EXPECT_EQ(SampleU(form, snap), (std::vector<double>{0.0, 1.0}));
  EXPECT_NEAR(snap->distance, 0.34, 1e-5);
  EXPECT_TRUE(snap->inside_leaf);

  // With (0,1) invalid, the edges into it weigh ΔG(valid, invalid) = 1: D to
  // (0,0) = 0.4*0.9 + 0.4*1 = 0.76, to (1,1) = 0.6*1 + 0.6*0.5 = 0.9, so
  // (1,0) at 0.6*0.9 + 0.4*0.5 = 0.74 wins.
  Skewed holed(false);
  const sampling::Form form2 = Sample(holed, UnitSquare(), 1, 0);
  const auto snap2 = SnapToValidSample(form2, form2.space(), {0.4, 0.4});
  ASSERT_TRUE(snap2);
  EXPECT_EQ(SampleU(form2, snap2), (std::vector<double>{1.0, 0.0}));
  EXPECT_NEAR(snap2->distance, 0.74, 1e-5);
  EXPECT_FALSE(SnapToValidSample(form2, form2.space(), {0.4, 1.4}));
}

TEST(ViewerSnap, FallsBackToTheNearestValidSampleOutsideValidLeaves) {
  Gap gap;
  const sampling::Form form = Sample(gap, UnitSquare(), 5, 3);
  // x = 0.5 lies in the middle of the gap, in leaves whose corners are all
  // invalid; the nearest valid samples are (0.3, 0.4) and (0.7, 0.4),
  // equally far: the lower id wins, and ids ascend with the key within the
  // round that created both, so x = 0.3.
  const auto snap = SnapToValidSample(form, form.space(), {0.5, 0.4});
  ASSERT_TRUE(snap);
  EXPECT_FALSE(snap->inside_leaf);
  EXPECT_DOUBLE_EQ(form.samples[snap->sample].u[0], 0.3);
  EXPECT_DOUBLE_EQ(form.samples[snap->sample].u[1], 0.4);
  // A point in a valid leaf snaps inside it.
  const auto inside = SnapToValidSample(form, form.space(), {0.05, 0.05});
  ASSERT_TRUE(inside);
  EXPECT_TRUE(inside->inside_leaf);
  EXPECT_TRUE(form.samples[inside->sample].outcome.valid);
}

TEST(ViewerStartingPoints, OnePerComponentOfTheValidGraph) {
  // The valid samples of Gap form two components (x <= 0.3 and x >= 0.7) with
  // no leaf edge between them: farthest-point sampling seeds both first. The
  // customiser serves these points for a run directory (cache::ChooseStartingPoints,
  // the rule the artifact's starting points follow).
  Gap gap;
  const sampling::Form form = Sample(gap, UnitSquare(), 5, 3);
  cache::StartingPointOptions options;
  options.count = 2;
  const auto points = cache::ChooseStartingPoints(form, options);
  ASSERT_EQ(points.size(), 2u);
  const double x0 = form.samples[points[0].sample_id].u[0], x1 = form.samples[points[1].sample_id].u[0];
  EXPECT_TRUE((x0 <= 0.3 && x1 >= 0.7) || (x0 >= 0.7 && x1 <= 0.3)) << x0 << " " << x1;
  EXPECT_NE(points[0].component, points[1].component);
  for (const auto& p : points) EXPECT_TRUE(form.samples[p.sample_id].outcome.valid);
  // More points than samples: every valid sample at most once.
  options.count = 1000;
  std::set<std::int64_t> distinct;
  const auto many = cache::ChooseStartingPoints(form, options);
  for (const auto& p : many) distinct.insert(p.sample_id);
  EXPECT_EQ(distinct.size(), many.size());
}

TEST(ViewerMaterials, WeightAndCostFromVolumeDensityAndPrice) {
  // 1 cm^3 of PLA (1.24 g/cm^3, 20 per kg): 1.24 g costing 0.0248.
  const auto r = MaterialReadouts(1000.0, {{"PLA", 1.24, 20.0}, {"resin", 1.12, 60.0}});
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0].name, "PLA");
  EXPECT_DOUBLE_EQ(r[0].weight_g, 1.24);
  EXPECT_DOUBLE_EQ(r[0].cost, 0.0248);
  EXPECT_DOUBLE_EQ(r[1].weight_g, 1.12);
  EXPECT_NEAR(r[1].cost, 0.0672, 1e-15);
}

}  // namespace
}  // namespace fabatlas::viewer
