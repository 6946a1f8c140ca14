// Collision resolution of reconfigurables (Reconfigurables, Secs. 6.4–6.6;
// docs/swept.md "Resolution"): the paper's Fig. 15 case, where the spatial
// normal at first contact points along the motion and only the spacetime
// normal points the way out, and automatic resolution of the folding bench,
// proved by the design's own checks.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "design_files.h"
#include "fabatlas/design/design_at_point.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/design/resolution_hint.h"
#include "fabatlas/design/resolve_collisions.h"
#include "fabatlas/error.h"

using namespace fabatlas;
using fabatlas::testing::TempDesign;

namespace {

// Fig. 15 in 3D: tests/design/data/hooks_fig15.yaml (a grey hook sliding
// over a green one; lifting it by more than 5 mm clears them).
std::string Hooks() {
  std::ifstream in(fabatlas::testing::SourceDir() / "tests/design/data/hooks_fig15.yaml");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}
const std::string kHooks = Hooks();

TEST(DesignResolve, Fig15SpacetimeNormalPointsUpWhereTheFirstContactNormalDoesNot) {
  const design::Design d = design::LoadDesign(TempDesign(kHooks));
  const design::Point u = design::ParsePoint(d, "", "--at");
  const design::HintSummary h = design::ResolutionHints(d, u);
  EXPECT_FALSE(h.sample.valid);
  EXPECT_EQ(h.sample.failure, design::kCollision);
  ASSERT_EQ(h.intervals.size(), 1u);
  const auto& i = h.intervals[0];
  EXPECT_EQ(i.object_a, "green");
  EXPECT_EQ(i.object_b, "grey");
  EXPECT_NEAR(i.t_begin, 5.0 / 12, 2.0 / 120);
  EXPECT_NEAR(i.t_end, 7.0 / 12, 2.0 / 120);
  const auto& n = i.normal;
  // Sec. 6.1: at first contact the touching faces are vertical planes, the
  // normal horizontal (back along the motion), with no vertical component.
  ASSERT_TRUE(n.has_first_contact);
  EXPECT_NEAR(n.first_contact_t, 5.0 / 12, 1.0 / 120);
  EXPECT_LT(n.first_contact_normal[0], -0.99);
  EXPECT_NEAR(n.first_contact_normal[2], 0.0, 0.05);
  // Eq. 2: entering and leaving cancel along x; the way out is up.
  EXPECT_GT(n.spacetime_normal[2], 0.95) << n.spacetime_normal[0] << " " << n.spacetime_normal[1];
  EXPECT_NEAR(n.spacetime_normal[1], 0.0, 0.05);
  EXPECT_GT(n.energy, 0.0);
  // Eq. 3 in the parameters: lift, not dx.
  ASSERT_EQ(h.pairs.size(), 1u);
  const auto& p = h.pairs[0];
  EXPECT_GT(p.descent.at("lift"), 0.0);
  EXPECT_LT(std::abs(p.descent.at("dx")), 0.1 * p.descent.at("lift"));
  // One resolution step (the hint with the line search's magnitude) clears
  // it, as the design's own check says; the edit is a lift of about 5 mm.
  ASSERT_TRUE(p.step.count("lift"));
  EXPECT_EQ(p.energy_after, 0.0);
  design::Point stepped = u;
  for (const auto& [name, v] : p.step) stepped[name] += v;
  const design::SampleResult after = design::EvaluateSample(d, stepped);
  EXPECT_TRUE(after.valid) << after.failure << ": " << after.failure_reason;
  EXPECT_GT(stepped.at("lift"), 5.0 - 1.0);  // within a voxel of the analytic 5 mm
  EXPECT_LT(stepped.at("lift"), 5.0 + 3.0);
  EXPECT_LT(std::abs(stepped.at("dx")), 1.0);
}

TEST(DesignResolve, Fig15AutomaticResolutionTakesOneStep) {
  const design::Design d = design::LoadDesign(TempDesign(kHooks));
  const design::ResolveSummary r = design::ResolveCollisions(d, design::ParsePoint(d, "", "--at"));
  EXPECT_TRUE(r.resolved) << r.failure_after << ": " << r.reason_after;
  EXPECT_EQ(r.failure_before, design::kCollision);
  EXPECT_EQ(r.steps.size(), 1u);
  EXPECT_GT(r.energy_before, 0.0);
  EXPECT_EQ(r.energy_after, 0.0);
  EXPECT_TRUE(design::EvaluateSample(d, r.after).valid);
}

// The folding bench (configs/designs/bench_table.yaml): the armrests' lower
// edge swings on a circle of radius sqrt(320^2 + (hinge_offset + 40)^2)
// about the hinge and clears the seat (top at z = 450) when
// armrest_height + hinge_offset - sqrt(320^2 + (hinge_offset + 40)^2) > 450.
// At (650, 50) that margin is -82.4 mm: it collides.
TEST(DesignResolve, FoldingBenchResolvedWithinItsParameters) {
  const design::Design d = design::LoadDesign(fabatlas::testing::SourceDir() / "configs/designs/bench_table.yaml");
  const design::Point u = design::ParsePoint(d, "armrest_height=650,hinge_offset=50", "--at");
  const design::ResolveSummary r = design::ResolveCollisions(d, u);
  EXPECT_EQ(r.failure_before, design::kCollision);
  ASSERT_TRUE(r.resolved) << r.failure_after << ": " << r.reason_after;
  const design::SampleResult after = design::EvaluateSample(d, r.after);
  EXPECT_TRUE(after.valid) << after.failure << ": " << after.failure_reason;
  // The analytic clearance condition holds, give or take a voxel (10 mm).
  const double a = r.after.at("armrest_height"), o = r.after.at("hinge_offset");
  EXPECT_GT(a + o - std::hypot(320.0, o + 40), 450 - 10);
  // Both parameters raise the swing; the edit stays within the ranges.
  EXPECT_GT(r.edit.at("armrest_height"), 0.0);
  EXPECT_GT(r.edit_size, 0.0);
  EXPECT_LE(r.edit_size, std::sqrt(2.0));
  // The resolved design written as YAML loads back at that point.
  const design::Design written = design::ParseDesign(design::DesignTextAt(d, r.after), "resolved.yaml");
  EXPECT_EQ(design::DefaultPoint(written), r.after);
}

// Precompute's verdict (EvaluateSample): a collision that resolution within
// the check's `repair_with` parameters resolves is `repairable`; one it
// cannot resolve (dx only shifts when the hooks meet) stays `collision`, as
// does every collision of a design that declares no such parameters.
TEST(DesignResolve, RepairableOnlyWithinTheDeclaredParameters) {
  auto with = [](const std::string& names) {
    std::string text = kHooks;
    const std::string check = "time_steps: 121}";
    text.replace(text.find(check), check.size(), "time_steps: 121, repair_with: \"" + names + "\"}");
    return design::LoadDesign(TempDesign(text));
  };
  const design::SampleResult lift = design::EvaluateSample(with("lift"), design::DefaultPoint(with("lift")));
  EXPECT_EQ(lift.failure, design::kRepairable) << lift.failure_reason;
  EXPECT_NE(lift.failure_reason.find("repairable: lift +"), std::string::npos) << lift.failure_reason;
  const design::SampleResult dx = design::EvaluateSample(with("dx"), design::DefaultPoint(with("dx")));
  EXPECT_EQ(dx.failure, design::kCollision) << dx.failure_reason;
  const design::Design plain = design::LoadDesign(TempDesign(kHooks));
  EXPECT_EQ(design::EvaluateSample(plain, design::DefaultPoint(plain)).failure, design::kCollision);
  // A name that is not an exposed real parameter is refused at load.
  try {
    with("lift, nope");
    ADD_FAILURE() << "loaded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("repair_with: 'nope' is not an exposed real parameter"), std::string::npos)
        << e.what();
  }
}

TEST(DesignResolve, RejectsUnknownParametersAndDesignsWithoutTransitions) {
  const design::Design d = design::LoadDesign(TempDesign(kHooks));
  design::ResolutionOptions o;
  o.parameters = {"nope"};
  EXPECT_THROW(design::ResolutionHints(d, design::DefaultPoint(d), o), InputError);
  const design::Design plain = design::LoadDesign(
      TempDesign("name: p\nparameters:\n  r: {type: real, min: 1, max: 2}\ntree: {op: sphere, radius: r}\n"));
  EXPECT_THROW(design::ResolveCollisions(plain, design::DefaultPoint(plain)), InputError);
}

}  // namespace
