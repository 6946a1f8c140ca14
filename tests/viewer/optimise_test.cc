// Objective queries and Pareto fronts (viewer/optimise.h, pareto_front.h) on
// a form sampled from the closed-form hollow cylinder of
// tests/sampling/analytic_designs.h: outer radius R in [5, 20], wall t in
// [0.5, 5], height 10 mm, valid iff t >= t_min(R) = 0.5 + 0.01 R^2, volume
// V(R, t) = 10 pi (R^2 - (R - t)^2) = 10 pi (2 R t - t^2). V grows with t
// (for t < R) and with R, so
//   - the lightest valid tube of radius R has the wall t_min(R);
//   - the front of volume (min) against radius (max) is the curve
//     V*(R) = V(R, t_min(R)), one lightest tube per radius;
// and the form's answers are conservative approximations of these whose
// error is bounded by one bootstrap cell (3 mm of R, 0.9 mm of t).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>

#include "../sampling/analytic_designs.h"
#include "fabatlas/error.h"
#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sampling/executor.h"
#include "fabatlas/viewer/leaf_corners.h"
#include "fabatlas/viewer/optimise.h"
#include "fabatlas/viewer/pareto_front.h"
#include "fabatlas/viewer/property_limits.h"
#include "fabatlas/viewer/valid_region.h"

namespace fabatlas::viewer {
namespace {

using sampling::testing::HollowCylinder2D;
using sampling::testing::HollowCylinderVolume;

double TMin(double R) { return 0.5 + 0.01 * R * R; }
double V(double R, double t) { return HollowCylinderVolume(R, t, 10.0); }

class Cylinder : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    HollowCylinder2D cylinder;
    sampling::DesignSpace space(HollowCylinder2D::Dimensions(), 5);
    sampling::ThreadPoolExecutor executor(1);
    sampling::SamplingOptions options;
    options.max_depth = 4;
    options.dg_threshold = 0.1;
    form_ = new sampling::Form(sampling::SampleDesignSpace(space, cylinder, executor, options).form);
    corners_ = new LeafCorners(*form_);
  }
  static void TearDownTestSuite() {
    delete corners_;
    delete form_;
  }
  static OptimiseResult Run(const std::string& objective, bool maximise, const std::string& hold,
                            const sampling::Form* form = nullptr) {
    OptimiseOptions o;
    o.terms = ParseObjective(objective);
    o.maximise = maximise;
    o.hold = ParseHolds(hold, form_->space());
    return Optimise(form ? *form : *form_, *corners_, {}, o);
  }
  static sampling::Form* form_;
  static LeafCorners* corners_;
};
sampling::Form* Cylinder::form_ = nullptr;
LeafCorners* Cylinder::corners_ = nullptr;

TEST_F(Cylinder, LightestValidTubeOfAGivenRadiusHasTheThinnestValidWall) {
  // R = 14 is a bootstrap grid line (samples lie on it: the answer is a
  // sample); R = 10 lies inside leaves (the answer interpolates along R
  // between two samples, exactly here since V is linear in R at fixed t).
  for (const double R : {14.0, 10.0}) {
    SCOPED_TRACE("R = " + std::to_string(R));
    const OptimiseResult r = Run("volume_mm3", false, "outer_radius=" + std::to_string(R));
    ASSERT_TRUE(r.found);
    EXPECT_DOUBLE_EQ(r.u[0], R);
    const double t = r.u[1];
    EXPECT_TRUE(HollowCylinder2D::TrulyValid(r.u));  // conservative: never below t_min
    EXPECT_GE(t, TMin(R));
    EXPECT_LT(t, TMin(R + 3.0) + 0.9);  // within one bootstrap cell of the analytic wall
    EXPECT_NEAR(r.values[0], V(R, t), 1e-9 * V(R, t));
    EXPECT_LT(r.objective, V(R, TMin(R + 3.0) + 0.9));
    // The same point the sliders reach: the low end of the valid interval
    // of the wall through R.
    const auto valid = ValidIntervals(*form_, form_->space(), *corners_, {R, 3.0}, 1);
    ASSERT_FALSE(valid.empty());
    EXPECT_DOUBLE_EQ(t, valid.front().lo);
    EXPECT_TRUE(IsValidPoint(*form_, form_->space(), *corners_, r.u));
    if (R == 14.0) {
      ASSERT_GE(r.sample, 0);
      EXPECT_EQ(form_->samples[r.sample].u, r.u);
      EXPECT_DOUBLE_EQ(r.values[0], form_->samples[r.sample].outcome.properties.at("volume_mm3"));
    } else {
      EXPECT_EQ(r.sample, -1);
      EXPECT_EQ(r.corners.size(), 2u);
    }
  }
}

TEST_F(Cylinder, GlobalOptimaAreAtTheAnalyticCorners) {
  // Lightest of all: the smallest radius with its thinnest valid wall,
  // t_min(5) = 0.75.
  const OptimiseResult lightest = Run("volume_mm3", false, "");
  ASSERT_TRUE(lightest.found);
  EXPECT_DOUBLE_EQ(lightest.u[0], 5.0);
  EXPECT_GE(lightest.u[1], TMin(5.0));
  EXPECT_LT(lightest.u[1], TMin(5.0) + 0.9);
  EXPECT_DOUBLE_EQ(lightest.objective, V(5.0, lightest.u[1]));
  EXPECT_GE(lightest.sample, 0);
  // Heaviest: R = 20, t = 5 (valid: t_min(20) = 4.5), a corner of the space.
  const OptimiseResult heaviest = Run("volume_mm3", true, "");
  ASSERT_TRUE(heaviest.found);
  EXPECT_EQ(heaviest.u, (std::vector<double>{20.0, 5.0}));
  EXPECT_NEAR(heaviest.objective, V(20.0, 5.0), 1e-9 * V(20.0, 5.0));
  // A weighted sum: -volume is maximising volume.
  const OptimiseResult negated = Run("volume_mm3=-1", false, "");
  EXPECT_EQ(negated.u, heaviest.u);
  EXPECT_DOUBLE_EQ(negated.objective, -heaviest.objective);
}

TEST_F(Cylinder, LargestRadiusForAHeldWallIsTheAnalyticBound) {
  // A parameter as the objective: with t = 1 held, valid iff R <= sqrt(50).
  const OptimiseResult r = Run("outer_radius", true, "wall=1");
  ASSERT_TRUE(r.found);
  EXPECT_DOUBLE_EQ(r.u[1], 1.0);
  EXPECT_LE(r.u[0], std::sqrt(50.0) + 1e-12);
  EXPECT_GT(r.u[0], std::sqrt(50.0) - 3.0);
  EXPECT_DOUBLE_EQ(r.objective, r.u[0]);  // a parameter interpolates exactly
  const auto valid = ValidIntervals(*form_, form_->space(), *corners_, {6.0, 1.0}, 0);
  ASSERT_EQ(valid.size(), 1u);
  EXPECT_DOUBLE_EQ(r.u[0], valid.front().hi);
}

TEST_F(Cylinder, LimitsBoundTheAnswer) {
  // Largest radius with volume <= 1000 mm^3: the lightest tube of radius R
  // weighs V*(R) = V(R, t_min(R)), increasing in R, so the bound R_lim
  // solves V*(R) = 1000 (bisection).
  double lo = 5, hi = 20;
  for (int k = 0; k < 200; ++k) {
    const double mid = (lo + hi) / 2;
    (V(mid, TMin(mid)) <= 1000 ? lo : hi) = mid;
  }
  const sampling::Form limited = ApplyLimits(*form_, ParseLimits("volume_mm3<=1000", {}), {});
  const OptimiseResult r = Run("outer_radius", true, "", &limited);
  ASSERT_TRUE(r.found);
  EXPECT_LE(r.u[0], lo + 1e-9);
  EXPECT_GT(r.u[0], lo - 3.0);
  EXPECT_LE(form_->samples[r.sample].outcome.properties.at("volume_mm3"), 1000.0);
  EXPECT_TRUE(HollowCylinder2D::TrulyValid(r.u));
  // Without the limit the largest radius is 20.
  EXPECT_DOUBLE_EQ(Run("outer_radius", true, "").u[0], 20.0);
}

TEST_F(Cylinder, ParetoFrontOfVolumeAgainstRadiusIsTheLightestTubePerRadius) {
  const ParetoFront front = ParetoFrontOf(*form_, {}, ParseParetoAxes("volume_mm3,max:outer_radius"));
  ASSERT_GE(front.points.size(), 6u);  // at least one per bootstrap grid line of R
  // Brute force over the valid samples: a point is on the front iff no valid
  // sample is at most as heavy and at least as wide, and better in one.
  std::vector<std::int64_t> valid;
  for (std::size_t i = 0; i < form_->samples.size(); ++i)
    if (form_->samples[i].outcome.valid) valid.push_back(static_cast<std::int64_t>(i));
  EXPECT_EQ(front.candidates, static_cast<std::int64_t>(valid.size()));
  const auto vol = [&](std::int64_t i) { return form_->samples[i].outcome.properties.at("volume_mm3"); };
  const auto rad = [&](std::int64_t i) { return form_->samples[i].u[0]; };
  std::set<std::pair<double, double>> brute;
  for (std::int64_t i : valid) {
    bool dominated = false;
    for (std::int64_t j : valid)
      if (vol(j) <= vol(i) && rad(j) >= rad(i) && (vol(j) < vol(i) || rad(j) > rad(i))) dominated = true;
    if (!dominated) brute.insert({vol(i), rad(i)});
  }
  std::set<std::pair<double, double>> got;
  for (const auto& p : front.points) got.insert({p.a, p.b});
  EXPECT_EQ(got, brute);
  // Against the analytic front: every point is a truly valid tube no lighter
  // than the lightest tube of its radius, within a cell of it, and the front
  // rises with the radius from the lightest tube (R = 5) to R = 20.
  for (std::size_t k = 0; k < front.points.size(); ++k) {
    const auto& p = front.points[k];
    const auto& u = form_->samples[p.sample].u;
    EXPECT_TRUE(HollowCylinder2D::TrulyValid(u));
    EXPECT_GE(p.a, V(p.b, TMin(p.b)) * (1 - 1e-12));
    EXPECT_LE(p.a, V(p.b, TMin(std::min(20.0, p.b + 3.0)) + 0.9));
    if (k) {
      EXPECT_GT(p.a, front.points[k - 1].a);
      EXPECT_GT(p.b, front.points[k - 1].b);
    }
  }
  EXPECT_DOUBLE_EQ(front.points.front().b, 5.0);
  EXPECT_DOUBLE_EQ(front.points.back().b, 20.0);
  EXPECT_DOUBLE_EQ(front.points.front().a, Run("volume_mm3", false, "").objective);
}

TEST_F(Cylinder, BadQueriesAreOneLineInputErrors) {
  EXPECT_THROW(Run("mass", false, ""), InputError);
  EXPECT_THROW(Run("volume_mm3=abc", false, ""), InputError);
  EXPECT_THROW(Run("volume_mm3=1,", false, ""), InputError);
  EXPECT_THROW(Run("", false, ""), InputError);
  EXPECT_THROW(Run("volume_mm3", false, "outer_radius=99"), InputError);
  EXPECT_THROW(Run("volume_mm3", false, "outer_radius"), InputError);
  EXPECT_THROW(Run("volume_mm3", false, "girth=3"), InputError);
  EXPECT_THROW(Run("volume_mm3", false, "wall=1,wall=2"), InputError);
  EXPECT_THROW(ParseParetoAxes("volume_mm3"), InputError);
  EXPECT_THROW(ParetoFrontOf(*form_, {}, ParseParetoAxes("volume_mm3,volume_mm3")), InputError);
  try {
    Run("mass", false, "");
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos);
    EXPECT_NE(what.find("volume_mm3"), std::string::npos) << what;  // lists what is known
    EXPECT_NE(what.find("outer_radius"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace fabatlas::viewer
