// Swept volumes against analytic solids (issue 7, "must be shown").
#include "fabatlas/swept/swept_volume.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "fabatlas/error.h"
#include "fabatlas/mesh/enclosed_volume.h"
#include "test_shapes.h"

namespace fabatlas::swept {
namespace {

constexpr double kPi = std::numbers::pi;

double CapsuleVolume(double r, double length) { return kPi * r * r * length + 4.0 / 3.0 * kPi * r * r * r; }

TEST(SweptVolume, SphereAlongSegmentIsCapsule) {
  const auto sphere = testing::IcoSphere(5.0, 5);  // 20480 triangles
  const auto motion = RigidMotion::Line({0, 0, 0}, {20, 0, 0});
  SweptVolumeOptions o;
  o.voxel_size = 0.25;
  o.offset = 0.5;
  SweptVolumeSummary s;
  const auto field = ComputeSweptDistance(sphere, motion, o, &s);
  EXPECT_GE(s.time_steps, 81);  // 20 mm at <= one voxel per step
  // Zero level set: capsule of radius 5; offset surface: radius 5.5.
  const double v0 = mesh::EnclosedVolume(field.Surface(0.0));
  const double v1 = mesh::EnclosedVolume(field.Surface(0.5));
  EXPECT_NEAR(v0 / CapsuleVolume(5.0, 20.0), 1.0, 0.01);
  EXPECT_NEAR(v1 / CapsuleVolume(5.5, 20.0), 1.0, 0.01);
  // Distances at points with known answers (capsule axis on x from 0 to 20).
  ASSERT_GE(field.band_half_width(), 1.0);
  EXPECT_NEAR(field.Value({10, 5.8, 0}), 0.8, 0.05);
  EXPECT_NEAR(field.Value({-5.7, 0, 0}), 0.7, 0.05);
  EXPECT_NEAR(field.Value({10, 0, 4.5}), -0.5, 0.05);
  EXPECT_LT(field.Value({10, 0, 0}), 0.0);  // deep inside: flood-filled negative
}

TEST(SweptVolume, BoxTurningAboutOffAxisIsAnnulus) {
  // Box x in [4,8], y in [-1,1], z in [-3,3] turning 360 degrees about the z
  // axis: the swept solid is the annulus 4 <= r <= sqrt(8^2 + 1^2), height 6.
  const auto box = testing::BoxMesh({4, -1, -3}, {8, 1, 3});
  const auto motion = RigidMotion::Turn({0, 0, 1}, 360, {0, 0, 0});
  SweptVolumeOptions o;
  o.voxel_size = 0.2;
  const auto field = ComputeSweptDistance(box, motion, o);
  const double expected = kPi * (65.0 - 16.0) * 6.0;
  EXPECT_NEAR(mesh::EnclosedVolume(field.Surface(0.0)) / expected, 1.0, 0.01);
  ASSERT_GE(field.band_half_width(), 0.6);
  EXPECT_NEAR(field.Value({0, 0, 0}), field.band_half_width(), 1e-6);  // 4 mm away: clamped to the band
  EXPECT_NEAR(field.Value({0, -6, 2.7}), -0.3, 0.05);                  // 0.3 mm inside the top face
  EXPECT_NEAR(field.Value({-3.7, 0, 0}), 0.3, 0.05);                   // in the hole
}

TEST(SweptVolume, CoarseTimeStepsWidenTheBandAndStaySigned) {
  // Only 3 poses 8 mm apart for a radius-5 sphere: the band grows to cover
  // the jump, so the centre of the middle sphere (3 mm outside the first
  // pose) still ends at -5 and not at +3.
  const auto sphere = testing::IcoSphere(5.0, 4);
  std::vector<Transform> poses(3);
  for (int i = 0; i < 3; ++i) poses[i].translation = {8.0 * i, 0, 0};
  SweptVolumeOptions o;
  o.voxel_size = 0.25;
  SweptVolumeSummary s;
  const auto field = ComputeSweptDistance(sphere, poses, o, &s);
  EXPECT_GE(s.band_half_width, 8.0);
  EXPECT_NEAR(field.Value({8, 0, 0}), -5.0, 0.05);
  EXPECT_NEAR(field.Value({4, 0, 0}), -1.0, 0.05);                    // min of the two spheres' distances
  EXPECT_NEAR(field.Value({4, 3.5, 0}), std::sqrt(28.25) - 5, 0.05);  // the waist is outside
}

TEST(SweptVolume, SolidResultMatchesMesh) {
  const auto sphere = testing::IcoSphere(3.0, 4);
  SweptVolumeOptions o;
  o.voxel_size = 0.25;
  o.offset = 0.5;
  geometry::GridSpec g;
  g.voxel_size = 0.25;
  const auto solid = SweptOffsetSolid(g, sphere, RigidMotion::Line({0, 0, 0}, {0, 0, 10}), o);
  EXPECT_NEAR(solid.Volume() / CapsuleVolume(3.5, 10.0), 1.0, 0.02);
}

TEST(SweptVolume, SolidBodyAlongSegmentIsCapsule) {
  geometry::GridSpec g;
  g.voxel_size = 0.2;
  const auto ball = geometry::Sphere(g, 3.0);
  SweptVolumeOptions o;
  o.voxel_size = 0.2;
  const auto field = ComputeSweptDistance(ball, RigidMotion::Line({0, 0, 0}, {0, 8, 0}), o);
  EXPECT_NEAR(mesh::EnclosedVolume(field.Surface(0.0)) / CapsuleVolume(3.0, 8.0), 1.0, 0.01);
  EXPECT_THROW(ComputeSweptDistance(geometry::Solid(), RigidMotion(), o), InputError);
}

TEST(SweptVolume, BadInputIsInputError) {
  const auto sphere = testing::IcoSphere(1.0, 1);
  SweptVolumeOptions o;
  o.voxel_size = -1;
  EXPECT_THROW(ComputeSweptDistance(sphere, RigidMotion(), o), InputError);
  EXPECT_THROW(ComputeSweptDistance(mesh::TriangleMesh{}, RigidMotion()), InputError);
  auto broken = sphere;
  broken.triangles[0][1] = 9999;
  EXPECT_THROW(ComputeSweptDistance(broken, RigidMotion()), InputError);
  o = {};
  o.max_active_voxels = 10;
  EXPECT_THROW(ComputeSweptDistance(sphere, RigidMotion(), o), ResourceError);
}

}  // namespace
}  // namespace fabatlas::swept
