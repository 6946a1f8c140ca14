// Collision intervals of a scripted scene against hand-computed time spans.
#include "fabatlas/swept/spacetime_collision.h"

#include <gtest/gtest.h>

#include <cmath>

#include "fabatlas/error.h"
#include "test_shapes.h"

namespace fabatlas::swept {
namespace {

TEST(SpacetimeCollision, BoxThroughBoxMatchesHandComputedSpan) {
  // A: unit cube [0,1]^3, static. B: 0.5-cube centred at (x(t), 0.5, 0.5)
  // with x(t) = -3 + 6t. They touch or overlap while x + 0.25 >= 0 and
  // x - 0.25 <= 1, i.e. t in [2.75/6, 4.25/6] = [0.4583, 0.7083].
  // C: a cube far away (z = 10) moving along y: never collides.
  std::vector<MovingPart> parts(3);
  parts[0].mesh = testing::BoxMesh({0, 0, 0}, {1, 1, 1});
  parts[1].mesh = testing::BoxMesh({-0.25, 0.25, 0.25}, {0.25, 0.75, 0.75});
  parts[1].motion = RigidMotion::Line({-3, 0, 0}, {3, 0, 0});
  parts[2].mesh = testing::BoxMesh({0, 0, 10}, {1, 1, 11});
  parts[2].motion = RigidMotion::Line({0, -5, 0}, {0, 5, 0});
  SpacetimeOptions o;
  o.time_steps = 121;  // dt = 1/120; B moves 0.05 mm per step
  const CollisionReport r = DetectCollisions(parts, o);
  ASSERT_EQ(r.intervals.size(), 1u);
  const auto& c = r.intervals[0];
  EXPECT_EQ(c.part_a, 0);
  EXPECT_EQ(c.part_b, 1);
  const double dt = 1.0 / 120;
  EXPECT_NEAR(c.t_begin, 2.75 / 6, dt + 1e-12);
  EXPECT_NEAR(c.t_end, 4.25 / 6, dt + 1e-12);
  EXPECT_GE(c.t_begin, 2.75 / 6 - 1e-9 - dt);
  // Where: B's y/z slab inside A, x across all of A.
  EXPECT_NEAR(c.where.min[0], 0.0, 0.05 + 1e-9);
  EXPECT_NEAR(c.where.max[0], 1.0, 0.05 + 1e-9);
  EXPECT_NEAR(c.where.min[1], 0.25, 1e-12);
  EXPECT_NEAR(c.where.max[1], 0.75, 1e-12);
  EXPECT_NEAR(c.where.min[2], 0.25, 1e-12);
  EXPECT_NEAR(c.where.max[2], 0.75, 1e-12);
  EXPECT_EQ(r.proxies, 3u * 120u);
}

// A 1 mm plate flies through a 1 mm wall between two time samples (it moves
// 10 mm per step): sampled alone the transition looks collision-free;
// conservative advancement between the samples reports the crossing with
// its time span. Plate x in [x(t) - 0.5, x(t) + 0.5], x(t) = -495 + 1000 t
// (samples at x = ..., -5, 5, ...); wall x in [0, 1]: they touch while
// x(t) + 0.5 >= 0 and x(t) - 0.5 <= 1, t in [494.5, 496.5] / 1000.
TEST(SpacetimeCollision, ThinPlateCrossingThinWallBetweenSamplesIsCaught) {
  std::vector<MovingPart> parts(2);
  parts[0].mesh = testing::BoxMesh({0, -10, -10}, {1, 10, 10});   // the wall, static
  parts[1].mesh = testing::BoxMesh({-0.5, -5, -5}, {0.5, 5, 5});  // the plate
  parts[1].motion = RigidMotion::Line({-495, 0, 0}, {505, 0, 0});
  SpacetimeOptions o;
  o.time_steps = 101;
  o.continuous = false;
  EXPECT_TRUE(DetectCollisions(parts, o).collision_free());  // the samples alone miss it
  o.continuous = true;
  const CollisionReport r = DetectCollisions(parts, o);
  ASSERT_EQ(r.intervals.size(), 1u);
  const CollisionInterval& c = r.intervals[0];
  EXPECT_EQ(c.part_a, 0);
  EXPECT_EQ(c.part_b, 1);
  // To the contact tolerance (1e-5 x 20 mm extent = 0.2 micrometre, 2e-7
  // in t).
  EXPECT_NEAR(c.t_begin, 0.4945, 1e-6);
  EXPECT_NEAR(c.t_end, 0.4965, 1e-6);
  EXPECT_NEAR(c.where.min[0], 0.0, 1e-3);
  EXPECT_NEAR(c.where.max[0], 1.0, 1e-3);
  EXPECT_NEAR(c.where.min[1], -5.0, 1e-9);
  EXPECT_NEAR(c.where.max[1], 5.0, 1e-9);
  EXPECT_GE(r.continuous_searches, 1u);
  EXPECT_GT(r.distance_queries, 2u);
}

// A thin blade (10 mm long, 0.1 mm thick) turning a full circle about z in
// four 90-degree steps sweeps through a 0.2 mm cube at 45 degrees, radius
// 7 mm, between the samples at 0 and 90 degrees: the samples alone miss it,
// the continuous test reports it with its time span (below).
TEST(SpacetimeCollision, FastTurningBladeThroughSmallCubeBetweenSamplesIsCaught) {
  std::vector<MovingPart> parts(2);
  parts[0].mesh = testing::BoxMesh({4.85, 4.85, -0.1}, {5.05, 5.05, 0.1});
  parts[1].mesh = testing::BoxMesh({0, -0.05, -1}, {10, 0.05, 1});
  parts[1].motion = RigidMotion::Turn({0, 0, 1}, 360, {0, 0, 0});
  SpacetimeOptions o;
  o.time_steps = 5;
  o.continuous = false;
  EXPECT_TRUE(DetectCollisions(parts, o).collision_free());
  o.continuous = true;
  const CollisionReport r = DetectCollisions(parts, o);
  ASSERT_EQ(r.intervals.size(), 1u);
  const CollisionInterval& c = r.intervals[0];
  // In the blade's frame turned by a, a point (x, y) is at
  // y' = -x sin a + y cos a. The leading side y' = +0.05 first reaches the
  // cube's corner at the lowest angle, (5.05, 4.85): a1 = atan2(4.85, 5.05)
  // - asin(0.05 / r); the trailing side y' = -0.05 last leaves the corner at
  // the highest angle, (4.85, 5.05): a2 = atan2(5.05, 4.85) + asin(0.05 / r),
  // r = |corner| (both corners have the same radius). t = a / 2 pi:
  // [0.1196, 0.1304].
  const double r1 = std::hypot(5.05, 4.85);
  const double a1 = std::atan2(4.85, 5.05) - std::asin(0.05 / r1);
  const double a2 = std::atan2(5.05, 4.85) + std::asin(0.05 / r1);
  const double two_pi = 2 * 3.14159265358979323846;
  EXPECT_NEAR(c.t_begin, a1 / two_pi, 1e-5);
  EXPECT_NEAR(c.t_end, a2 / two_pi, 1e-5);
}

TEST(SpacetimeCollision, TwoSeparateIntervalsAreReportedInTimeOrder) {
  // A small cube orbits the z axis at radius 3; two static cubes sit on the
  // orbit at 0 and 180 degrees.
  std::vector<MovingPart> parts(3);
  parts[0].mesh = testing::BoxMesh({2.5, -0.5, -0.5}, {3.5, 0.5, 0.5});    // at angle 0
  parts[1].mesh = testing::BoxMesh({-3.5, -0.5, -0.5}, {-2.5, 0.5, 0.5});  // at angle 180
  parts[2].mesh = testing::BoxMesh({2.9, -0.1, -0.1}, {3.1, 0.1, 0.1});    // small cube at angle 0
  parts[2].motion = RigidMotion::Turn({0, 0, 1}, 360, {0, 0, 0});
  SpacetimeOptions o;
  o.time_steps = 361;
  const CollisionReport r = DetectCollisions(parts, o);
  // The small cube (half size 0.1, centre at radius 3, angle a) reaches the
  // static cube's side y = 0.5 while 3 sin a - 0.1 (cos a + sin a) <= 0.5,
  // i.e. 2.9 sin a - 0.1 cos a <= 0.5: a <= 11.93 degrees (t <= 0.03314).
  // Around the static cube at 180 degrees the same holds by symmetry.
  ASSERT_EQ(r.intervals.size(), 3u);
  EXPECT_EQ(r.intervals[0].part_a, 0);
  EXPECT_DOUBLE_EQ(r.intervals[0].t_begin, 0.0);
  EXPECT_NEAR(r.intervals[0].t_end, 11.93 / 360, 1.0 / 360);
  EXPECT_LE(r.intervals[0].t_end, 11.93 / 360);
  EXPECT_EQ(r.intervals[1].part_a, 1);
  EXPECT_EQ(r.intervals[1].part_b, 2);
  EXPECT_LT(r.intervals[1].t_begin, 0.5);
  EXPECT_GT(r.intervals[1].t_end, 0.5);
  EXPECT_NEAR(r.intervals[1].t_end - 0.5, 0.5 - r.intervals[1].t_begin, 1.0 / 360 + 1e-12);  // symmetric
  EXPECT_DOUBLE_EQ(r.intervals[2].t_end, 1.0);
  // The all-pairs and Embree broad phases find the same intervals from the
  // same candidates.
  for (auto b : {SpacetimeOptions::BroadPhase::kAllPairs, SpacetimeOptions::BroadPhase::kEmbree}) {
    o.broad_phase = b;
    const CollisionReport all = DetectCollisions(parts, o);
    ASSERT_EQ(all.intervals.size(), r.intervals.size());
    EXPECT_EQ(all.candidate_pairs, r.candidate_pairs);
    EXPECT_EQ(all.exact_tests, r.exact_tests);
    for (std::size_t i = 0; i < r.intervals.size(); ++i) {
      EXPECT_EQ(all.intervals[i].t_begin, r.intervals[i].t_begin);
      EXPECT_EQ(all.intervals[i].t_end, r.intervals[i].t_end);
      EXPECT_EQ(all.intervals[i].part_a, r.intervals[i].part_a);
      EXPECT_EQ(all.intervals[i].part_b, r.intervals[i].part_b);
    }
  }
}

TEST(SpacetimeCollision, BadInputIsInputError) {
  std::vector<MovingPart> parts(2);
  parts[0].mesh = testing::BoxMesh({0, 0, 0}, {1, 1, 1});
  parts[1].mesh = testing::BoxMesh({0, 0, 0}, {1, 1, 1});
  parts[1].mesh.triangles.pop_back();
  EXPECT_THROW(DetectCollisions(parts), InputError);
  SpacetimeOptions o;
  o.time_steps = 1;
  parts[1].mesh = parts[0].mesh;
  EXPECT_THROW(DetectCollisions(parts, o), InputError);
}

TEST(SpacetimeCollision, StillPartsAreTestedOnceAndCollideThroughout) {
  // Two overlapping cubes that never move, and a third far away sliding by:
  // the still pair collides over the whole transition after one exact test.
  std::vector<MovingPart> parts(3);
  parts[0].mesh = testing::BoxMesh({0, 0, 0}, {1, 1, 1});
  parts[1].mesh = testing::BoxMesh({0.5, 0.5, 0.5}, {1.5, 1.5, 1.5});
  parts[2].mesh = testing::BoxMesh({0, 0, 10}, {1, 1, 11});
  parts[2].motion = RigidMotion::Line({0, -5, 0}, {0, 5, 0});
  SpacetimeOptions o;
  o.time_steps = 51;
  const CollisionReport r = DetectCollisions(parts, o);
  ASSERT_EQ(r.intervals.size(), 1u);
  EXPECT_EQ(r.intervals[0].t_begin, 0.0);
  EXPECT_EQ(r.intervals[0].t_end, 1.0);
  EXPECT_EQ(r.exact_tests, 1u);
  EXPECT_NEAR(r.intervals[0].where.min[0], 0.5, 1e-12);
  EXPECT_NEAR(r.intervals[0].where.max[0], 1.0, 1e-12);
}

}  // namespace
}  // namespace fabatlas::swept
