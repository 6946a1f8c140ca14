// Works-like prototypes (Koo et al.): relationships, joints and conflicts
// against analytic outcomes.
#include <gtest/gtest.h>

#include <cmath>

#include "fabatlas/error.h"
#include "fabatlas/prototype/solve.h"
#include "fabatlas/testing/paths.h"

namespace fabatlas::prototype {
namespace {

std::filesystem::path Example(const std::string& name) {
  return testing::SourceDir() / "configs" / "prototypes" / (name + ".yaml");
}

bool Mentions(const std::vector<std::string>& items, const std::string& what) {
  for (const auto& s : items)
    if (s.find(what) != std::string::npos) return true;
  return false;
}

// The flap of tests/prototype/data/flap.yaml (gap 30): swung 90 degrees, its
// top face lies on the plane y = 10 - height and must be flush with the wall
// 35 mm in front of the hinge, so the height must become exactly 35 mm.
TEST(PrototypeSolve, HingedFlapFlushWithWallHasAnalyticHeight) {
  Prototype p = LoadPrototype(testing::SourceDir() / "tests/prototype/data/flap.yaml");
  SolveSummary s = SolvePrototype(p);
  ASSERT_TRUE(s.satisfiable) << s.Explain();
  auto f = s.cuboids.at("flap");
  EXPECT_NEAR(f[5] - f[4], 35.0, 1e-4);
  EXPECT_NEAR(f[4], 0.0, 1e-4);  // least squares: only the top moves
  EXPECT_NEAR(s.deviation, 5.0, 1e-4);
}

// A part translated by 40 mm along y between two configurations: the
// position constraint (x2 - x1).(xm - xB) = 0 puts the parent pivot on the
// perpendicular bisector, y_B = y_A + 20, i.e. b = 10 + 20 - 100 = -70, and
// the link has the same length in both configurations.
TEST(PrototypeSolve, DoublePivotPositionConstraintForATranslation) {
  Prototype p = ParsePrototype(R"(
parts:
  frame: {box: [0, 50, 0, 200, -50, -10], hold: [x0, x1, y0, y1, z0, z1]}
  panel: {box: [0, 20, 0, 20, 0, 60], hold: [x0, x1, y0, y1, z0, z1]}
joints:
  dp: {type: double_pivot, child: panel, parent: frame, face: x0, pivot_child: [0.5, 0.5], pivot_parent: [0.5, 0.5]}
configurations:
  moved: {dp: {angle: 0, offset: [0, 40, 0], free: false}}
)", "translate.yaml");
  SolveSummary s = SolvePrototype(p);
  ASSERT_TRUE(s.satisfiable) << s.Explain();
  ASSERT_EQ(s.pivots.size(), 1u);
  const PivotSolution& q = s.pivots[0];
  EXPECT_NEAR(q.b, -70.0, 1e-3);
  EXPECT_NEAR(q.parent_pivot[1], 30.0, 1e-3);
  std::array<double, 3> moved = q.child_pivot;
  moved[1] += 40;
  auto dist = [](const std::array<double, 3>& u, const std::array<double, 3>& v) {
    return std::hypot(u[0] - v[0], u[1] - v[1], u[2] - v[2]);
  };
  EXPECT_NEAR(dist(q.child_pivot, q.parent_pivot), dist(moved, q.parent_pivot), 1e-3);
  EXPECT_GE(q.link_length + 1e-6, q.link_length_bound);
}

// A door that must cover an opening of at least 100 mm while a user
// constraint keeps it at most 80 mm wide: reported as exactly those three
// groups, not the unrelated flush relationship.
TEST(PrototypeSolve, ConflictingConstraintsAreNamed) {
  Prototype p = ParsePrototype(R"(
parts:
  body: {box: [0, 120, 0, 50, 0, 50], hold: [x0, x1, y0, y1, z0, z1],
         cavities: {opening: {box: [10, 110, 0, 40, 5, 45], open: y0}}}
  door: {box: [10, 110, -3, 0, 5, 45]}
  knob: {box: [50, 60, -8, -3, 20, 30]}
relationships:
  - {type: cover, name: door covers the opening, covering: [door.y1], covered: [body.opening.y0]}
  - {type: geometric, name: narrow door, expression: "door.w <= 80"}
  - {type: geometric, name: wide opening, expression: "body.opening.w >= 100"}
  - {type: flush, name: knob on the door, faces: [knob.y1, door.y0]}
)", "conflict.yaml");
  SolveSummary s = SolvePrototype(p);
  ASSERT_FALSE(s.satisfiable);
  EXPECT_TRUE(Mentions(s.conflicts, "door covers the opening")) << s.Explain();
  EXPECT_TRUE(Mentions(s.conflicts, "narrow door")) << s.Explain();
  EXPECT_TRUE(Mentions(s.conflicts, "wide opening")) << s.Explain();
  EXPECT_EQ(s.conflicts.size(), 3u) << s.Explain();
  EXPECT_FALSE(Mentions(s.conflicts, "knob on the door")) << s.Explain();
  EXPECT_NE(s.Explain().find("conflicting constraints"), std::string::npos);
  // Without the narrow-door constraint it solves, the door just covering.
  p.relationships.erase(p.relationships.begin() + 1);
  SolveSummary ok = SolvePrototype(p);
  ASSERT_TRUE(ok.satisfiable) << ok.Explain();
  EXPECT_LE(ok.cuboids.at("door")[0], 10 + 1e-4);
  EXPECT_GE(ok.cuboids.at("door")[1], 110 - 1e-4);
}

// Cabinet: the doors cover the upper opening, share its width equally
// (symmetry), match its height (cover + fit when turned in), the lid just
// covers the top and the drawer front ends flush.
TEST(PrototypeSolve, CabinetRelationshipsHold) {
  Prototype p = LoadPrototype(Example("cabinet"));
  SolveSummary s = SolvePrototype(p);
  ASSERT_TRUE(s.satisfiable) << s.Explain();
  auto up = s.cuboids.at("body.upper"), l = s.cuboids.at("door_l"), r = s.cuboids.at("door_r");
  EXPECT_NEAR(l[0], up[0], 1e-4);
  EXPECT_NEAR(r[1], up[1], 1e-4);
  EXPECT_NEAR(l[1], r[0], 1e-4);
  EXPECT_NEAR(l[1] - l[0], (up[1] - up[0]) / 2, 1e-4);
  EXPECT_NEAR(l[4], up[4], 1e-4);
  EXPECT_NEAR(l[5], up[5], 1e-4);
  // Turned 90 degrees into the compartment the door's width lies along y.
  EXPECT_LE(l[1] - l[0] + s.free_values.at("door_l_hinge@open.s"), up[3] - up[2] + 1e-4);
  auto lid = s.cuboids.at("lid"), body = s.cuboids.at("body");
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(lid[k], body[k], 1e-4);
  EXPECT_NEAR(s.cuboids.at("drawer")[2] + s.free_values.at("drawer_slide@closed.s"), body[2], 1e-4);
  EXPECT_EQ(s.constraints > 0, true);
}

// Crate bed: boards of equal thickness, folded headboard on the bed top and
// footboard on the headboard; each double pivot's link equally long before
// and after folding (checked through the mirror pivots agreeing).
TEST(PrototypeSolve, CrateBedFolds) {
  Prototype p = LoadPrototype(Example("crate_bed"));
  SolveSummary s = SolvePrototype(p);
  ASSERT_TRUE(s.satisfiable) << s.Explain();
  auto h = s.cuboids.at("headboard"), f = s.cuboids.at("footboard");
  EXPECT_NEAR(h[3] - h[2], f[3] - f[2], 1e-4);
  ASSERT_EQ(s.pivots.size(), 4u);
  EXPECT_NEAR(s.pivots[0].a, s.pivots[1].a, 1e-6);
  EXPECT_NEAR(s.pivots[0].link_length, s.pivots[1].link_length, 1e-6);
  for (const auto& q : s.pivots) EXPECT_GT(q.link_length, 0);
}

// Sofa bunk: unfolded, the legs reach from the ground to the bunk on the
// headrest, so their length equals the headrest height H; their top faces
// overlap the bunk by min_overlap = 1 mm, so the (symmetric) legs start at
// least 1 mm inside the bunk's ends, and folded they must not overlap:
// satisfiable iff 2 H + 2 <= S.
TEST(PrototypeSolve, SofaBunkHeadrestHeightBound) {
  for (double h : {90.0, 128.9, 129.0, 129.1, 140.0}) {
    Prototype p = LoadPrototype(Example("sofa_bunk"), {{"headrest_height", h}, {"sofa_length", 260}});
    SolveSummary s = SolvePrototype(p);
    bool expected = 2 * h + 2 <= 260 + 1e-9;
    ASSERT_EQ(s.satisfiable, expected) << "H=" << h << ": " << s.Explain();
    if (s.satisfiable) {
      auto leg = s.cuboids.at("leg_l");
      EXPECT_NEAR(leg[1] - leg[0], h, 1e-3);
      EXPECT_NEAR(s.cuboids.at("headrest")[5], h, 1e-4);
    } else {
      EXPECT_TRUE(Mentions(s.conflicts, "folded legs fit within the bunk")) << s.Explain();
    }
  }
}

TEST(PrototypeSolve, BadInputNamesThePlace) {
  try {
    ParsePrototype("parts:\n  a: {box: [0, 1, 0, 1, 0, 1]}\njoints:\n  j: {type: hinge, child: a, parent: b, axis: x, at: [a.y0, a.z0]}\n",
                   "bad.yaml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.yaml:4:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("unknown part 'b'"), std::string::npos) << e.what();
  }
  // A missing key has no line of its own: the error names the file alone.
  try {
    ParsePrototype("parts:\n  a: {box: [0, 1, 0, 1, 0, 1]}\njoints:\n  j: {child: a, parent: a}\n", "bad.yaml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("bad.yaml: ", 0), 0u) << e.what();
  }
  EXPECT_THROW(LoadPrototype(Example("cabinet"), {{"no_such", 1}}), InputError);
  EXPECT_THROW(ParsePrototype("parts:\n  a: {box: [0, 1, 0, 1, 1, 0]}\n", "x.yaml"), InputError);
}

}  // namespace
}  // namespace fabatlas::prototype
