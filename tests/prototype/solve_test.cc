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
)",
                               "translate.yaml");
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
)",
                               "conflict.yaml");
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

// Koo et al. Table 1, "Statistics for fabricated prototypes": joints by type
// and constraints (functional relationships, geometric constraints) of the
// eight examples. The seed's text gives the two constraint columns row by
// row: 7 1 / 2 1 / 3 1 / 5 1 / 2 0 / 2 1 / 2 1 / 2 0.
struct Table1Row {
  const char* file;
  int hinge, slide, sliding_hinge, double_pivot, functional, geometric;
};
constexpr Table1Row kTable1[] = {
    {"cabinet", 1, 1, 3, 0, 7, 1},   {"crate_bar", 2, 5, 0, 0, 2, 1}, {"crate_bed", 0, 0, 0, 4, 3, 1},
    {"sofa_bunk", 2, 0, 0, 2, 5, 1}, {"printer", 2, 3, 0, 0, 2, 0},   {"cellphone", 1, 1, 0, 0, 2, 1},
    {"tablet", 1, 1, 0, 0, 2, 1},    {"toolbox", 1, 1, 0, 0, 2, 0},
};

TEST(PrototypeSolve, TheEightExamplesSolveWithTable1sCounts) {
  for (const Table1Row& row : kTable1) {
    Prototype p = LoadPrototype(Example(row.file));
    int joints[4] = {0, 0, 0, 0}, functional = 0, geometric = 0;
    for (const Joint& j : p.joints) ++joints[static_cast<int>(j.type)];
    for (const Relationship& r : p.relationships) ++(r.type == RelationType::kGeometric ? geometric : functional);
    EXPECT_EQ(joints[static_cast<int>(JointType::kHinge)], row.hinge) << row.file;
    EXPECT_EQ(joints[static_cast<int>(JointType::kSlide)], row.slide) << row.file;
    EXPECT_EQ(joints[static_cast<int>(JointType::kSlidingHinge)], row.sliding_hinge) << row.file;
    EXPECT_EQ(joints[static_cast<int>(JointType::kDoublePivot)], row.double_pivot) << row.file;
    EXPECT_EQ(functional, row.functional) << row.file;
    EXPECT_EQ(geometric, row.geometric) << row.file;
    SolveSummary s = SolvePrototype(p);
    EXPECT_TRUE(s.satisfiable) << row.file << ": " << s.Explain();
    EXPECT_LE(s.max_violation, 1e-4) << row.file;
  }
}

// A part of two cuboids (Koo et al. Sec. 3): a 10 mm block with a 5 mm cap
// on it, x0 aligned. Made 20 mm tall (bottom held), the block carries the
// cap's bottom to 20; the cap's top (15 in the input) is then pushed to
// 20 + min_size = 21 and no further (Eq. 4 moves coordinates as little as
// possible). Moving the cap's x0 to 3 moves the block's with it.
TEST(PrototypeSolve, PiecesStayOnTheirCuboid) {
  SolveSummary s = SolvePrototype(ParsePrototype(R"(
parts:
  block:
    box: [0, 10, 0, 10, 0, 10]
    hold: [x1, y0, y1, z0]
    pieces: {cap: {box: [0, 8, 2, 8, 10, 15], align: [x0]}}
relationships:
  - {type: geometric, name: tall block, expression: "block.h == 20"}
  - {type: geometric, name: cap moved, expression: "block.cap.x0 == 3"}
)",
                                                 "pieces.yaml"));
  ASSERT_TRUE(s.satisfiable) << s.Explain();
  auto cap = s.cuboids.at("block.cap");
  EXPECT_NEAR(cap[4], 20, 1e-4);
  EXPECT_NEAR(cap[5], 21, 1e-4);
  EXPECT_NEAR(cap[1], 8, 1e-4);
  EXPECT_NEAR(s.cuboids.at("block")[0], 3, 1e-4);
}

// A whole part of two cuboids fits inside a room z 1..12 (Sec. 4.2 with
// Box(P) the union's box): the block's bottom rises to 1, the cap's top drops
// to 12, the contact between them stays at 10.
TEST(PrototypeSolve, AllCuboidsOfAPartFitInside) {
  SolveSummary s = SolvePrototype(ParsePrototype(R"(
parts:
  case:
    box: [-5, 15, -5, 15, 0, 13]
    hold: [x0, x1, y0, y1, z0, z1]
    cavities: {room: {box: [-4, 14, -4, 14, 1, 12], hold: [z0, z1]}}
  block:
    box: [0, 10, 0, 10, 0, 10]
    pieces: {cap: {box: [2, 8, 2, 8, 10, 15]}}
relationships:
  - {type: fit, name: block in the room, inner: [block], outer: case.room}
)",
                                                 "fit_pieces.yaml"));
  ASSERT_TRUE(s.satisfiable) << s.Explain();
  EXPECT_NEAR(s.cuboids.at("block")[4], 1, 1e-4);
  EXPECT_NEAR(s.cuboids.at("block")[5], 10, 1e-4);
  EXPECT_NEAR(s.cuboids.at("block.cap")[4], 10, 1e-4);
  EXPECT_NEAR(s.cuboids.at("block.cap")[5], 12, 1e-4);
}

// A slide on rails (Koo et al. Sec. 7) keeps the child on the parent: a
// 30 mm carriage on a 100 mm bed, asked to travel as far as it can (a free
// slide pulled towards 1000 mm), stops when it overlaps the bed by its
// min_size (1 mm): at 100 - 1 - 0 = 99 mm from x0 = 0.
TEST(PrototypeSolve, SlideOnRailsStaysOnItsParent) {
  Prototype p = ParsePrototype(R"(
parts:
  bed:      {box: [0, 100, 0, 40, 0, 10], hold: [x0, x1, y0, y1, z0, z1]}
  carriage: {box: [0, 30, 10, 30, 10, 20], hold: [x0, x1, y0, y1, z1]}
joints:
  s: {type: slide, child: carriage, parent: bed, axis: x, on: [carriage.z0, bed.z1]}
configurations:
  far: {s: {free: true, guess: 1000}}
)",
                               "rails.yaml");
  SolveSummary s = SolvePrototype(p);
  ASSERT_TRUE(s.satisfiable) << s.Explain();
  EXPECT_NEAR(s.free_values.at("s@far.s"), 99.0, 1e-3);
  EXPECT_NEAR(s.cuboids.at("carriage")[4], 10.0, 1e-4);  // rail faces coplanar
}

// The jewellery box's discrete edits (Koo et al. Sec. 8): the three fronts
// just cover the chest (z 5..55, held), packed. Removing the middle drawer leaves
// two fronts that must meet; least squares moves both free edges (20 and 38)
// equally, to 29. Removing the bottom drawer instead stretches the middle
// front down to the chest's floor (5) and leaves the top front alone.
TEST(PrototypeSolve, JewelleryBoxRemovingACompartmentResolves) {
  Prototype p = LoadPrototype(Example("jewellery_box"));
  SolveSummary s = SolvePrototype(p);
  ASSERT_TRUE(s.satisfiable) << s.Explain();
  EXPECT_NEAR(s.cuboids.at("drawer_2")[4], 20, 1e-4);

  Prototype without_2 = RemovePart(p, "drawer_2");
  EXPECT_EQ(without_2.parts.size(), 3u);
  EXPECT_EQ(without_2.joints.size(), 2u);
  ASSERT_EQ(without_2.relationships.size(), 2u);
  EXPECT_EQ(without_2.relationships[0].a.size(), 2u);
  SolveSummary a = SolvePrototype(without_2);
  ASSERT_TRUE(a.satisfiable) << a.Explain();
  EXPECT_NEAR(a.cuboids.at("drawer_1")[4], 5, 1e-4);
  EXPECT_NEAR(a.cuboids.at("drawer_1")[5], 29, 1e-3);
  EXPECT_NEAR(a.cuboids.at("drawer_3")[4], 29, 1e-3);
  EXPECT_NEAR(a.cuboids.at("drawer_3")[5], 55, 1e-4);
  EXPECT_EQ(a.cuboids.count("drawer_2.tray"), 0u);

  SolveSummary b = SolvePrototype(RemovePart(p, "drawer_1"));
  ASSERT_TRUE(b.satisfiable) << b.Explain();
  EXPECT_NEAR(b.cuboids.at("drawer_2")[4], 5, 1e-4);
  EXPECT_NEAR(b.cuboids.at("drawer_2")[5], 38, 1e-3);
  EXPECT_NEAR(b.cuboids.at("drawer_3")[4], 38, 1e-3);

  EXPECT_THROW(RemovePart(p, "drawer_4"), InputError);
}

// Removing a part takes what hangs from it: the printer's flap carries the
// extension; the flap's flush relationship goes with them.
TEST(PrototypeSolve, RemovingAPartRemovesWhatHangsFromIt) {
  Prototype p = RemovePart(LoadPrototype(Example("printer")), "flap");
  EXPECT_EQ(p.PartIndex("flap"), -1);
  EXPECT_EQ(p.PartIndex("extension"), -1);
  EXPECT_EQ(p.joints.size(), 3u);
  ASSERT_EQ(p.relationships.size(), 1u);
  EXPECT_EQ(p.relationships[0].type, RelationType::kFit);
  for (const Configuration& c : p.configurations) {
    EXPECT_EQ(c.values.count("flap_hinge"), 0u);
    EXPECT_EQ(c.values.count("extension_slide"), 0u);
  }
  EXPECT_TRUE(SolvePrototype(p).satisfiable);
}

TEST(PrototypeSolve, BadInputNamesThePlace) {
  try {
    ParsePrototype(
        "parts:\n  a: {box: [0, 1, 0, 1, 0, 1]}\njoints:\n  j: {type: hinge, child: a, parent: b, axis: x, at: [a.y0, "
        "a.z0]}\n",
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
  // A piece named like a coordinate would make "a.x0" ambiguous; a piece
  // apart from its cuboid is not part of it.
  for (const char* bad : {"parts:\n  a: {box: [0, 1, 0, 1, 0, 1], pieces: {x0: {box: [1, 2, 0, 1, 0, 1]}}}\n",
                          "parts:\n  a: {box: [0, 1, 0, 1, 0, 1], pieces: {p: {box: [3, 4, 0, 1, 0, 1]}}}\n"}) {
    try {
      SolvePrototype(ParsePrototype(bad, "pieces.yaml"));
      FAIL() << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("pieces.yaml:2:", 0), 0u) << e.what();
    }
  }
}

}  // namespace
}  // namespace fabatlas::prototype
