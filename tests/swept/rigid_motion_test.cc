// Keyframed rigid motions: Bezier translation and slerp rotation against
// closed-form values.
#include "fabatlas/swept/rigid_motion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "fabatlas/error.h"

namespace fabatlas::swept {
namespace {

void ExpectNear(const Vec3& a, const Vec3& b, double tol = 1e-12) {
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], b[k], tol) << "component " << k;
}

TEST(RigidMotion, CubicBezierTranslationMatchesBernsteinForm) {
  RigidMotion m;
  m.translation = {{{0, 0, 0}, {3, 0, 0}, {3, 6, 0}, {0, 6, 3}}};
  ExpectNear(m.At(0).Apply({1, 2, 3}), {1, 2, 3});
  ExpectNear(m.At(1).Apply({0, 0, 0}), {0, 6, 3});
  // T(1/2) = (P0 + 3 P1 + 3 P2 + P3) / 8
  ExpectNear(m.At(0.5).Apply({0, 0, 0}), {(0 + 9 + 9 + 0) / 8.0, (0 + 0 + 18 + 6) / 8.0, 3 / 8.0});
  // Times outside [0,1] clamp.
  ExpectNear(m.At(2.0).Apply({0, 0, 0}), {0, 6, 3});
}

TEST(RigidMotion, FullTurnSlerpsThroughQuarterTurns) {
  const RigidMotion m = RigidMotion::Turn({0, 0, 1}, 360, {1, 0, 0});
  ASSERT_EQ(m.rotation_keys.size(), 5u);
  // About the pivot (1,0,0): the point (2,0,0) is at radius 1.
  ExpectNear(m.At(0.25).Apply({2, 0, 0}), {1, 1, 0});
  ExpectNear(m.At(0.5).Apply({2, 0, 0}), {0, 0, 0});
  ExpectNear(m.At(1.0).Apply({2, 0, 0}), {2, 0, 0});
  // Constant angular speed inside a key interval (slerp, not lerp).
  const double a = 2 * std::numbers::pi * 0.1;
  ExpectNear(m.At(0.1).Apply({2, 0, 0}), {1 + std::cos(a), std::sin(a), 0});
  ExpectNear(m.At(0.5).Apply({1, 0, 5}), {1, 0, 5});  // the pivot axis stays fixed
}

TEST(RigidMotion, InverseAndCompose) {
  RigidMotion m = RigidMotion::Turn({1, 2, 3}, 73, {0.5, -1, 2});
  m.translation = {{{1, 0, 0}, {2, 1, 0}, {0, 3, 1}, {4, 4, 4}}};
  const Transform f = m.At(0.37);
  const Vec3 x{0.3, -2.0, 7.5};
  ExpectNear(f.Inverse().Apply(f.Apply(x)), x, 1e-12);
  const Transform g = m.At(0.81);
  ExpectNear(f.Compose(g).Apply(x), f.Apply(g.Apply(x)), 1e-12);
  // Rigid: distances are preserved.
  const Vec3 y{4, 5, -6};
  const Vec3 fx = f.Apply(x), fy = f.Apply(y);
  EXPECT_NEAR(std::hypot(fx[0] - fy[0], fx[1] - fy[1], fx[2] - fy[2]),
              std::hypot(x[0] - y[0], x[1] - y[1], x[2] - y[2]), 1e-12);
}

TEST(RigidMotion, RelativeMotionIsMotionInOtherFrame) {
  const RigidMotion a = RigidMotion::Line({0, 0, 0}, {10, 0, 0});
  // Two parts moving together do not move relative to each other.
  const std::vector<Transform> together = SampleRelativeMotion(a, a, 5);
  ASSERT_EQ(together.size(), 5u);
  for (const auto& f : together) ExpectNear(f.Apply({1, 2, 3}), {1, 2, 3}, 1e-12);
  // B turns 90 degrees about z through the origin while A slides 10 mm
  // along x: in A's frame, B's point x is at R(90 t deg) x - (10 t, 0, 0).
  const RigidMotion b = RigidMotion::Turn({0, 0, 1}, 90, {0, 0, 0});
  const std::vector<Transform> rel = SampleRelativeMotion(a, b, 5);
  ASSERT_EQ(rel.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    const double t = i / 4.0, ang = 0.5 * std::acos(-1.0) * t;
    ExpectNear(rel[i].Apply({2, 0, 1}), {2 * std::cos(ang) - 10 * t, 2 * std::sin(ang), 1}, 1e-12);
  }
}

// The speed bound of conservative advancement: exact for a straight line at
// constant speed and a turn at constant angular speed, and never below the
// speed of a point of a curved, turning motion (central differences).
TEST(RigidMotion, SpeedBoundHoldsAndIsTightForSimpleMotions) {
  EXPECT_NEAR(RigidMotion::Line({0, 0, 0}, {3, 4, 0}).SpeedBound(100), 5.0, 1e-12);
  EXPECT_NEAR(RigidMotion::Turn({0, 0, 1}, 360, {0, 0, 0}).SpeedBound(3), 6 * std::acos(-1.0), 1e-9);
  RigidMotion m = RigidMotion::Turn({1, 2, 3}, 200, {0.5, -1, 2});
  m.translation = {{{0, 0, 0}, {20, 5, 0}, {-10, 15, 3}, {4, 4, 4}}};
  const Vec3 x{3, -2, 7};
  const double radius = std::hypot(x[0] - 0.5, x[1] + 1, x[2] - 2);
  const double bound = m.SpeedBound(radius);
  double fastest = 0;
  for (int i = 1; i < 999; ++i) {
    const double t = i / 1000.0, h = 1e-6;
    const Vec3 p = m.At(t + h).Apply(x), q = m.At(t - h).Apply(x);
    fastest = std::max(fastest, std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]) / (2 * h));
  }
  EXPECT_LE(fastest, bound);
  EXPECT_GT(fastest, 0.3 * bound);  // and not uselessly loose
}

TEST(RigidMotion, BadInputIsInputError) {
  RigidMotion m;
  m.rotation_keys = {{0, 0, 0, 0}, {1, 0, 0, 0}};
  EXPECT_THROW(m.At(0.1), InputError);
  EXPECT_THROW(RigidMotion().At(std::nan("")), InputError);
  EXPECT_THROW(Quaternion::FromAxisAngle({0, 0, 0}, 10), InputError);
}

}  // namespace
}  // namespace fabatlas::swept
