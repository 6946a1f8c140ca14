// Minimum clearance over a transition against analytic gaps.
#include "fabatlas/swept/spacetime_clearance.h"

#include <gtest/gtest.h>

#include <cmath>

#include "fabatlas/error.h"
#include "test_shapes.h"

namespace fabatlas::swept {
namespace {

TEST(SpacetimeClearance, PassingCubeKeepsTheFaceGap) {
  // A: unit cube [0,1]^3, static. B: unit cube at x in [2,3] sliding along
  // y from -5 to 5: while their y ranges overlap the faces x = 1 and x = 2
  // are 1 apart, and never closer.
  std::vector<MovingPart> parts(2);
  parts[0].mesh = testing::BoxMesh({0, 0, 0}, {1, 1, 1});
  parts[1].mesh = testing::BoxMesh({2, 0, 0}, {3, 1, 1});
  parts[1].motion = RigidMotion::Line({0, -5, 0}, {0, 5, 0});
  const ClearanceReport r = MinimumClearance(parts);
  EXPECT_NEAR(r.min_clearance, 1.0, 1e-12);
  EXPECT_EQ(r.part_a, 0);
  EXPECT_EQ(r.part_b, 1);
  // Reached where B's y range overlaps A's: y offset in [-1, 1], t in [0.4, 0.6].
  EXPECT_GE(r.t, 0.4 - 1e-12);
  EXPECT_LE(r.t, 0.6 + 1e-12);
  EXPECT_NEAR(r.point_b[0] - r.point_a[0], 1.0, 1e-12);
}

TEST(SpacetimeClearance, EdgeOverEdgeGapIsTheDiagonal) {
  // B lifted by 1.5 in z as well: the closest features are A's top edge
  // x = 1, z = 1 and B's bottom edge x = 2, z = 1.5: gap sqrt(1 + 0.25).
  std::vector<MovingPart> parts(2);
  parts[0].mesh = testing::BoxMesh({0, 0, 0}, {1, 1, 1});
  parts[1].mesh = testing::BoxMesh({2, 0, 1.5}, {3, 1, 2.5});
  parts[1].motion = RigidMotion::Line({0, -5, 0}, {0, 5, 0});
  EXPECT_NEAR(MinimumClearance(parts).min_clearance, std::sqrt(1.25), 1e-12);
}

TEST(SpacetimeClearance, OrbitingCubeIsClosestOnTheDiagonals) {
  // A: cube [-0.5, 0.5]^3 at the origin. B: cube of half size 0.1 centred at
  // (3, 0, 0) turning a full circle about z (its near face always faces the
  // axis). On the axes the gap is 3 - 0.1 - 0.5 = 2.4; on the diagonals A's
  // vertical edge x = y = 0.5 comes to 2.9 - sqrt(2)/2 = 2.19289 of B's near
  // face, first at 45 degrees (t = 0.125). That contact is edge-against-face
  // with the closest point inside A's edge, the case vertex-triangle
  // distances overestimate (spacetime_clearance.h): B's face corners, 0.1
  // to either side, are 2.1946 away. Samples every degree.
  std::vector<MovingPart> parts(2);
  parts[0].mesh = testing::BoxMesh({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5});
  parts[1].mesh = testing::BoxMesh({2.9, -0.1, -0.1}, {3.1, 0.1, 0.1});
  parts[1].motion = RigidMotion::Turn({0, 0, 1}, 360, {0, 0, 0});
  ClearanceOptions o;
  o.time_steps = 361;
  const ClearanceReport r = MinimumClearance(parts, o);
  const double exact = 2.9 - std::sqrt(0.5);
  EXPECT_GE(r.min_clearance, exact - 1e-12);
  EXPECT_LT(r.min_clearance, exact + 0.0025);  // well below the 2.4 on the axes
  EXPECT_NEAR(r.t, 0.125, 3.0 / 360);
  // Fewer queries than the vertices x samples x directions without pruning.
  EXPECT_LT(r.vertex_queries, 2u * 8u * 361u);
}

TEST(SpacetimeClearance, ApproachIsClosestAtTheEnd) {
  // B (a unit cube) slides from x = 5 to x = 2.25 towards A: clearance 1.25
  // at t = 1, and
  // a far third part does not change it.
  std::vector<MovingPart> parts(3);
  parts[0].mesh = testing::BoxMesh({0, 0, 0}, {1, 1, 1});
  parts[1].mesh = testing::BoxMesh({0, 0, 0}, {1, 1, 1});
  parts[1].motion = RigidMotion::Line({5, 0, 0}, {2.25, 0, 0});
  parts[2].mesh = testing::BoxMesh({0, 0, 100}, {1, 1, 101});
  const ClearanceReport r = MinimumClearance(parts);
  EXPECT_NEAR(r.min_clearance, 1.25, 1e-12);
  EXPECT_NEAR(r.t, 1.0, 1e-12);
  EXPECT_EQ(r.part_a, 0);
  EXPECT_EQ(r.part_b, 1);
}

TEST(SpacetimeClearance, MaxDistanceCapsTheSearchAndBadInputThrows) {
  std::vector<MovingPart> parts(2);
  parts[0].mesh = testing::BoxMesh({0, 0, 0}, {1, 1, 1});
  parts[1].mesh = testing::BoxMesh({10, 0, 0}, {11, 1, 1});
  ClearanceOptions o;
  o.max_distance = 5;
  EXPECT_EQ(MinimumClearance(parts, o).min_clearance, 5.0);
  o.max_distance = 20;
  EXPECT_NEAR(MinimumClearance(parts, o).min_clearance, 9.0, 1e-12);
  o.time_steps = 1;
  EXPECT_THROW(MinimumClearance(parts, o), InputError);
  parts[1].mesh.triangles.clear();
  EXPECT_THROW(MinimumClearance(parts), InputError);
}

}  // namespace
}  // namespace fabatlas::swept
