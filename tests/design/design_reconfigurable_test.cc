// Reconfigurable designs (docs/design-format.md "Reconfigurables"):
// objects with keyframed motions on the transitions of a state graph, the
// collision_free check (intervals against hand-computed spans, a colliding
// and a clear configuration, clearance against an analytic gap), the
// carve_swept operation, and one-line errors for bad files.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include <fstream>
#include <sstream>

#include "../../common/design/src/exact_boolean.h"
#include "../../common/design/src/operations.h"
#include "design_files.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/design/state_graph.h"
#include "fabatlas/error.h"
#include "fabatlas/mesh/enclosed_volume.h"

using namespace fabatlas;
using fabatlas::testing::TempDesign;

namespace {

design::SampleResult Evaluate(const design::Design& d, const std::string& at = "") {
  return design::EvaluateSample(d, design::ParsePoint(d, at, "--at"));
}

const design::CheckOutcome& Outcome(const design::SampleResult& r, const std::string& name) {
  for (const auto& c : r.checks)
    if (c.name == name) return c;
  ADD_FAILURE() << "no check " << name << " ran (failure: " << r.failure << ": " << r.failure_reason << ")";
  static design::CheckOutcome none;
  return none;
}

// A 20 mm post at the origin and a 10 mm cube sliding along x from -60 to
// +60 at height `dz` and lateral offset `dy`: with dy = dz = 0 they touch
// while |x(t)| <= 15, x(t) = -60 + 120 t, i.e. t in [0.375, 0.625]; with
// dy = 20 the gap between the faces y = 10 and y = 15 is 5 mm.
const char* kSlider = R"(name: slider
voxel_size: 0.5
parameters:
  dy: {type: real, min: 0, max: 40, default: 0}
objects:
  post: {op: box, size: [20, 20, 20]}
  cube:
    op: translate
    by: [0, dy, 0]
    children: [{op: box, size: [10, 10, 10]}]
states: [left, right]
transitions:
  - name: slide
    from: left
    to: right
    motions:
      cube: {translation: [[-60, 0, 0], [60, 0, 0]]}
tree:
  op: union
  children:
    - {op: object, object: post}
    - {op: object, object: cube}
checks:
  - {type: collision_free, time_steps: 121}
)";

TEST(DesignReconfigurable, CollisionIntervalMatchesHandComputedSpan) {
  const design::Design d = design::LoadDesign(TempDesign(kSlider));
  ASSERT_EQ(d.objects.size(), 2u);
  ASSERT_EQ(d.transitions.size(), 1u);
  EXPECT_EQ(d.transitions[0].name, "slide");
  const design::SampleResult r = Evaluate(d, "dy=0");
  EXPECT_FALSE(r.valid);
  EXPECT_EQ(r.failure, design::kCollision);
  const auto& c = Outcome(r, "collision_free");
  EXPECT_FALSE(c.passed);
  // One time step is 1 mm of travel; the level-set boxes are within a
  // fraction of a voxel (0.5 mm) of the exact ones.
  const double dt = 1.0 / 120;
  ASSERT_TRUE(c.measures.count("collision_t_begin")) << c.reason;
  EXPECT_NEAR(c.measures.at("collision_t_begin"), 0.375, 1.5 * dt);
  EXPECT_NEAR(c.measures.at("collision_t_end"), 0.625, 1.5 * dt);
  EXPECT_NE(c.reason.find("transition slide t in ["), std::string::npos) << c.reason;
  EXPECT_NE(c.reason.find("'post' and 'cube'"), std::string::npos) << c.reason;
  EXPECT_EQ(c.measures.at("min_clearance"), 0.0);
}

// The state graph the customiser plays (state_graph.h) is what the check
// tested: its intervals are the check's measures, its motions the file's
// (the cube at x = -60 + 120 t), its objects the level-set meshes.
TEST(DesignReconfigurable, StateGraphHoldsWhatTheCheckTested) {
  const design::Design d = design::LoadDesign(TempDesign(kSlider));
  const design::StateGraphResult r = design::EvaluateStateGraph(d, design::ParsePoint(d, "dy=0", "--at"));
  const auto& c = Outcome(r.sample, "collision_free");
  const design::StateGraph& g = r.graph;
  EXPECT_TRUE(g.collisions_checked);
  EXPECT_EQ(g.time_steps, 121);
  ASSERT_EQ(g.object_names, (std::vector<std::string>{"post", "cube"}));
  ASSERT_EQ(g.objects.size(), 2u);
  EXPECT_GT(g.objects[1].triangles.size(), 12u);
  ASSERT_EQ(g.transitions.size(), 1u);
  const auto& t = g.transitions[0];
  EXPECT_EQ(t.name, "slide");
  EXPECT_EQ(t.from, "left");
  EXPECT_EQ(t.to, "right");
  ASSERT_EQ(t.collisions.size(), 1u);
  EXPECT_EQ(t.collisions[0].t_begin, c.measures.at("collision_t_begin"));
  EXPECT_EQ(t.collisions[0].t_end, c.measures.at("collision_t_end"));
  EXPECT_EQ(t.collisions[0].part_a, 0);
  EXPECT_EQ(t.collisions[0].part_b, 1);
  ASSERT_EQ(t.motions.size(), 2u);
  for (const double time : {0.0, 0.25, 1.0}) {
    EXPECT_NEAR(t.motions[1].At(time).translation[0], -60 + 120 * time, 1e-9);
    EXPECT_EQ(t.motions[0].At(time).translation[0], 0.0);
  }
  // Clear: no intervals, the motions still there.
  const design::StateGraphResult clear = design::EvaluateStateGraph(d, design::ParsePoint(d, "dy=20", "--at"));
  EXPECT_TRUE(clear.sample.valid);
  ASSERT_EQ(clear.graph.transitions.size(), 1u);
  EXPECT_TRUE(clear.graph.transitions[0].collisions.empty());
  // Without a collision_free check: objects and motions, nothing checked.
  std::string text = kSlider;
  text.erase(text.find("checks:"));
  const design::Design unchecked = design::LoadDesign(TempDesign(text));
  const design::StateGraphResult u =
      design::EvaluateStateGraph(unchecked, design::ParsePoint(unchecked, "dy=0", "--at"));
  EXPECT_TRUE(u.sample.valid);
  EXPECT_FALSE(u.graph.collisions_checked);
  EXPECT_EQ(u.graph.objects.size(), 2u);
  ASSERT_EQ(u.graph.transitions.size(), 1u);
  EXPECT_TRUE(u.graph.transitions[0].collisions.empty());
  EXPECT_NEAR(u.graph.transitions[0].motions[1].At(1).translation[0], 60, 1e-9);
}

TEST(DesignReconfigurable, ClearConfigurationReportsTheAnalyticGap) {
  const design::Design d = design::LoadDesign(TempDesign(kSlider));
  const design::SampleResult r = Evaluate(d, "dy=20");
  ASSERT_TRUE(r.valid) << r.failure << ": " << r.failure_reason;
  ASSERT_TRUE(r.properties.count("min_clearance"));
  // Gap 20 - 10 - 5 = 5 mm, within one voxel.
  EXPECT_NEAR(r.properties.at("min_clearance"), 5.0, 0.5);
  const double at12 = Evaluate(d, "dy=32").properties.at("min_clearance");
  EXPECT_NEAR(at12, 17.0, 0.5);
}

TEST(DesignReconfigurable, RequiredClearanceFailsCloseCalls) {
  std::string text = kSlider;
  text.replace(text.find("time_steps: 121}"), 16, "time_steps: 121, clearance: 8}");
  const design::Design d = design::LoadDesign(TempDesign(text));
  const design::SampleResult close = Evaluate(d, "dy=20");
  EXPECT_FALSE(close.valid);
  EXPECT_EQ(close.failure, design::kTooLittleClearance);
  EXPECT_TRUE(Evaluate(d, "dy=30").valid);
}

// A sphere (r = 5) pushed through a 4 mm plate along z. Without carving the
// transition collides; carve_swept removes the 0.5 mm offset swept volume (a
// capsule, r = 5.5 through the plate: a cylindrical hole) and then the
// transition is collision-free.
std::string Plate(bool carve) {
  std::string plate = carve ? R"(
    op: carve_swept
    moving: ball
    transition: push
    offset: 0.5
    children: [{op: box, size: [40, 40, 4]}])"
                            : R"(
    op: box
    size: [40, 40, 4])";
  return std::string(R"(name: plate
voxel_size: 0.5
parameters:
  r: {type: real, min: 4, max: 6, default: 5}
objects:
  plate:)") +
         plate + R"(
  ball: {op: sphere, radius: r}
states: [above, below]
transitions:
  - name: push
    from: above
    to: below
    motions:
      ball: {translation: [[0, 0, 20], [0, 0, 10], [0, 0, -10], [0, 0, -20]]}
tree: {op: object, object: plate}
checks:
  - {type: collision_free, time_steps: 81}
properties: [volume]
)";
}

TEST(DesignReconfigurable, CarvingRemovesTheCollision) {
  const design::SampleResult before = Evaluate(design::LoadDesign(TempDesign(Plate(false))));
  EXPECT_FALSE(before.valid);
  EXPECT_EQ(before.failure, design::kCollision);
  const design::SampleResult after = Evaluate(design::LoadDesign(TempDesign(Plate(true))));
  ASSERT_TRUE(after.valid) << after.failure << ": " << after.failure_reason;
  // The hole is the offset capsule's cross-section: a cylinder of radius 5.5.
  const double expected = 40.0 * 40 * 4 - M_PI * 5.5 * 5.5 * 4;
  EXPECT_NEAR(after.properties.at("volume"), expected, 0.01 * expected);
  // The clearance is analytic: the ball (r = 5) slides through a hole of
  // r = 5.5, 0.5 mm away at every step inside the plate. Level-set surfaces
  // lie within a quarter voxel (0.125 mm) of the exact ones; measured 0.451.
  EXPECT_NEAR(after.properties.at("min_clearance"), 0.5, 0.125);
}

TEST(DesignReconfigurable, BadFilesGiveOneLineErrors) {
  auto error_of = [](const std::string& text) {
    try {
      design::LoadDesign(TempDesign(text));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::string unknown_object = kSlider;
  unknown_object.replace(unknown_object.find("      cube: {translation"), 11, "      cub:");
  EXPECT_NE(error_of(unknown_object).find("unknown object 'cub'"), std::string::npos) << error_of(unknown_object);
  std::string three_points = kSlider;
  three_points.replace(three_points.find("[[-60, 0, 0], [60, 0, 0]]"), 25, "[[-60, 0, 0], [0, 0, 0], [60, 0, 0]]");
  EXPECT_NE(error_of(three_points).find("2 points (a line) or 4 Bezier control points"), std::string::npos);
  std::string bad_state = kSlider;
  bad_state.replace(bad_state.find("from: left"), 10, "from: right");
  EXPECT_NE(error_of(bad_state).find("not the first state nor reached"), std::string::npos) << error_of(bad_state);
  std::string carve = Plate(true);
  carve.replace(carve.find("transition: push"), 16, "transition: pull");
  EXPECT_NE(error_of(carve).find("unknown transition 'pull'"), std::string::npos) << error_of(carve);
  std::string cycle = Plate(true);
  cycle.replace(cycle.find("ball: {op: sphere, radius: r}"), 29, "ball: {op: object, object: plate}");
  EXPECT_NE(error_of(cycle).find("depends on itself"), std::string::npos) << error_of(cycle);
  // Messages name the file and the place.
  EXPECT_NE(error_of(unknown_object).find("design.yaml:"), std::string::npos);
}

// The worker task kind TASK_KIND_SWEPT_VOLUME runs ComputeSweptVolume: the
// cutter of the plate's carve_swept node is the offset capsule of the ball's
// path, r = 5.5 from z = 20 to z = -20.
TEST(DesignReconfigurable, SweptVolumeTaskGivesTheOffsetCapsule) {
  const design::Design d = design::LoadDesign(TempDesign(Plate(true)));
  const design::Point u = design::DefaultPoint(d);
  const design::SweptVolumeResult r = design::ComputeSweptVolume(d, u, "object:plate");
  const double r5 = 5.5, length = 40;
  const double capsule = M_PI * r5 * r5 * length + 4.0 / 3.0 * M_PI * r5 * r5 * r5;
  // Within 2%: the ball is itself a 0.5 mm level set, meshed, then swept on a
  // second grid (each discretisation shaves a little off convex surfaces).
  EXPECT_NEAR(r.volume, capsule, 0.02 * capsule);
  EXPECT_GT(r.triangles, 1000u);
  EXPECT_GE(r.time_steps, 80);  // at most one voxel (0.5 mm) of travel per step over 40 mm
  EXPECT_EQ(r.surface_sha256.size(), 64u);
  EXPECT_EQ(design::ComputeSweptVolume(d, u, "object:plate").surface_sha256, r.surface_sha256);
  EXPECT_NE(design::ComputeSweptVolume(d, design::ParsePoint(d, "r=4", "--at"), "object:plate").surface_sha256,
            r.surface_sha256);
  EXPECT_THROW(design::ComputeSweptVolume(d, u, "object:ball"), InputError);
  EXPECT_THROW(design::ComputeSweptVolume(d, u, "root/7"), InputError);
}

// The two example designs of Reconfigurables (configs/designs): a known colliding
// and a known clear configuration of the folding bench (see the inequality in
// its header), and the carved cabinet insert at its default point.
TEST(DesignReconfigurable, BenchTableCollidesWhileFoldingOnlyWithLowArmrests) {
  const design::Design d = design::LoadDesign(fabatlas::testing::SourceDir() / "configs/designs/bench_table.yaml");
  // 650 + 150 - sqrt(320^2 + 190^2) = 427.8 < 450: the armrests dip into the
  // seat mid-fold, while both end states are clear.
  const design::SampleResult low = Evaluate(d, "armrest_height=650,hinge_offset=150");
  EXPECT_FALSE(low.valid);
  EXPECT_EQ(low.failure, design::kCollision);
  const auto& c = Outcome(low, "collision_free");
  EXPECT_GT(c.measures.at("collision_t_begin"), 0.0) << c.reason;
  EXPECT_LT(c.measures.at("collision_t_end"), 1.0) << c.reason;
  // 800 + 100 - sqrt(320^2 + 140^2) = 550.7: 100 mm above the seat top.
  const design::SampleResult high = Evaluate(d, "armrest_height=800,hinge_offset=100");
  ASSERT_TRUE(high.valid) << high.failure << ": " << high.failure_reason;
  EXPECT_NEAR(high.properties.at("min_clearance"), 100.7, 10.0);
}

TEST(DesignReconfigurable, CabinetInsertIsCarvedCollisionFree) {
  const design::Design d = design::LoadDesign(fabatlas::testing::SourceDir() / "configs/designs/cabinet_insert.yaml");
  // Default: the mug's top passes 20 + 40 + 100 = 160 mm, 40 mm under the
  // cabinet's top board; the carved foam keeps about the 3 mm offset.
  const design::SampleResult r = Evaluate(d);
  ASSERT_TRUE(r.valid) << r.failure << ": " << r.failure_reason;
  EXPECT_NEAR(r.properties.at("min_clearance"), 3.0, 1.5);
  // 40 + 40 + 140 = 220 > 200: the mug hits the top board while stowing
  // (on the way in, at the entry height, until it drops into its pocket).
  const design::SampleResult tall = Evaluate(d, "mug_height=140,pocket_floor=40");
  EXPECT_FALSE(tall.valid);
  EXPECT_EQ(tall.failure, design::kCollision);
  EXPECT_NE(Outcome(tall, "collision_free").reason.find("'cabinet' and 'mug'"), std::string::npos)
      << Outcome(tall, "collision_free").reason;
}

// The cabinet insert (configs/designs/cabinet_insert.yaml) with its foam
// block uncarved, carved exactly (the default) and carved by level-set
// difference (exact: false).
std::string CabinetInsert(const std::string& carve) {
  std::ifstream in(fabatlas::testing::SourceDir() / "configs/designs/cabinet_insert.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  const std::string node = "    op: carve_swept\n    moving: mug\n    transition: stow\n    offset: 3\n";
  const std::size_t at = s.find(node);
  if (at == std::string::npos) return "cabinet_insert.yaml no longer has the expected carve_swept node";
  if (carve == "none") s.replace(at, node.size(), "    op: translate\n    by: [0, 0, 0]\n");
  if (carve == "level_set") s.replace(at, node.size(), node + "    exact: false\n");
  return s;
}

// Before carving, the mug runs into the foam block while it is stowed; after
// exact carving the same transition is collision-free with about the 3 mm
// offset as clearance, and the exactly carved foam holds the same volume as
// the level-set carving (both re-voxelised on the 3 mm grid).
TEST(DesignReconfigurable, ExactCarvingRemovesTheCabinetInsertCollision) {
  const design::SampleResult before = Evaluate(design::LoadDesign(TempDesign(CabinetInsert("none"))));
  ASSERT_FALSE(before.valid);
  EXPECT_EQ(before.failure, design::kCollision);
  EXPECT_NE(Outcome(before, "collision_free").reason.find("'mug' and 'foam'"), std::string::npos)
      << Outcome(before, "collision_free").reason;
  const design::SampleResult exact = Evaluate(design::LoadDesign(TempDesign(CabinetInsert("exact"))));
  ASSERT_TRUE(exact.valid) << exact.failure << ": " << exact.failure_reason;
  EXPECT_NEAR(exact.properties.at("min_clearance"), 3.0, 1.5);
  const design::SampleResult level_set = Evaluate(design::LoadDesign(TempDesign(CabinetInsert("level_set"))));
  ASSERT_TRUE(level_set.valid) << level_set.failure << ": " << level_set.failure_reason;
  // The carve removed more than the mug's own volume (pi 40^2 100 plus the
  // handle), as the pocket is the mug swept in from the front. Uncarved:
  // cabinet 260 x 220 x 15 + 2 x 10 x 220 x 200, foam 200 x 200 x 150.
  const double uncarved = 260.0 * 220 * 15 + 2 * 10.0 * 220 * 200 + 200.0 * 200 * 150;
  const double removed = uncarved - exact.properties.at("volume");
  EXPECT_GT(removed, M_PI * 40 * 40 * 100);
  EXPECT_NEAR(exact.properties.at("volume"), level_set.properties.at("volume"), 0.01 * removed);
}

// Exact booleans reject bad meshes with a one-line sample failure, never a
// crash: two cubes sharing only an edge (not a manifold), two overlapping
// cubes in one mesh (self-intersecting), an open box.
TEST(DesignReconfigurable, ExactSubtractionRejectsBadMeshes) {
  auto cube = [](double x0, double y0, double z0, double s, mesh::TriangleMesh* m) {
    const auto base = static_cast<std::int32_t>(m->vertices.size());
    for (int k = 0; k < 8; ++k)
      m->vertices.push_back({x0 + s * (k & 1), y0 + s * ((k >> 1) & 1), z0 + s * ((k >> 2) & 1)});
    const int f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                          {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    for (const auto& t : f) m->triangles.push_back({base + t[0], base + t[1], base + t[2]});
  };
  mesh::TriangleMesh good;
  cube(0, 0, 0, 2, &good);
  mesh::TriangleMesh cutter;
  cube(1, 1, 1, 2, &cutter);
  const mesh::TriangleMesh carved = design::ExactMeshBoolean("difference", {good, cutter});
  EXPECT_NEAR(mesh::EnclosedVolume(carved), 7.0, 1e-9);  // 8 - 1 (the corner cube the cutter takes)

  auto failure_of = [&](const mesh::TriangleMesh& bad) {
    try {
      design::ExactMeshBoolean("difference", {good, bad});
    } catch (const design::SampleFailure& e) {
      EXPECT_EQ(e.type(), "no_geometry");
      return std::string(e.what());
    }
    return std::string("no failure");
  };
  mesh::TriangleMesh edge_pair;  // two cubes sharing the edge x = 1, y = 1
  cube(-1, -1, 0, 2, &edge_pair);
  cube(1, 1, 0, 2, &edge_pair);
  // Merge the shared edge's vertices so the mesh is non-manifold there.
  mesh::TriangleMesh merged = edge_pair;
  for (auto& t : merged.triangles)
    for (auto& i : t)
      for (std::int32_t j = 0; j < i; ++j)
        if (merged.vertices[j] == merged.vertices[i]) {
          i = j;
          break;
        }
  // The triangles around the shared edge are paired across the material,
  // so the two cubes touch along it and cut as a Nef polyhedron (as
  // OpenSCAD cuts them): each takes a 1 x 1 x 2 corner of the cube.
  EXPECT_NEAR(mesh::EnclosedVolume(design::ExactMeshBoolean("difference", {good, merged})), 8.0 - 2.0 - 2.0, 1e-9);
  mesh::TriangleMesh overlapping;
  cube(0, 0, 0, 2, &overlapping);
  cube(1, 1, 1, 2, &overlapping);
  EXPECT_NE(failure_of(overlapping).find("operand 1 intersects itself"), std::string::npos) << failure_of(overlapping);
  mesh::TriangleMesh open = cutter;
  open.triangles.pop_back();
  EXPECT_NE(failure_of(open).find("operand 1 is not closed"), std::string::npos) << failure_of(open);
}

}  // namespace
