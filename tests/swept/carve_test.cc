// Carving (Reconfigurables, Eq. 4): a sphere pushed through a plate collides; after
// carving its eps-offset swept volume from the plate, the exact collision
// check passes and the hole has the capsule's cross-section.
#include "fabatlas/swept/carve.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "fabatlas/error.h"
#include "fabatlas/mesh/enclosed_volume.h"
#include "test_shapes.h"

namespace fabatlas::swept {
namespace {

TEST(Carve, CarvedPlateNoLongerCollidesWithMovingSphere) {
  const auto plate = testing::BoxMesh({-6, -6, -1}, {6, 6, 1});
  const auto ball = testing::IcoSphere(2.0, 3);
  const RigidMotion still;
  const RigidMotion through = RigidMotion::Line({0, 0, -5}, {0, 0, 5});
  std::vector<Transform> check;
  for (int i = 0; i <= 100; ++i) check.push_back(through.At(i / 100.0));
  ASSERT_TRUE(CollidesAtAnyPose(plate, ball, check));

  SweptVolumeOptions o;
  o.voxel_size = 0.1;
  o.offset = 0.2;
  const auto carved = CarveSweptVolume(plate, still, ball, through, o);
  EXPECT_FALSE(CollidesAtAnyPose(carved, ball, check));
  // The plate keeps its outer faces exactly; the hole is a cylinder of radius
  // 2 + eps through the 2 mm plate (the capsule's straight part).
  const double expected = 12.0 * 12.0 * 2.0 - std::numbers::pi * 2.2 * 2.2 * 2.0;
  EXPECT_NEAR(mesh::EnclosedVolume(carved) / expected, 1.0, 0.01);
}

TEST(Carve, RelativeMotionInPartFrame) {
  // Both parts move together by the same translation: no relative motion, so
  // carving removes only the ball's own (offset) volume where they overlap.
  const auto plate = testing::BoxMesh({-6, -6, -1}, {6, 6, 1});
  const auto ball = testing::IcoSphere(2.0, 3);
  const RigidMotion shared = RigidMotion::Line({0, 0, 0}, {30, 0, 0});
  SweptVolumeOptions o;
  o.voxel_size = 0.1;
  o.offset = 0.2;
  const auto carved = CarveSweptVolume(plate, shared, ball, shared, o);
  // Sphere of radius 2.2 cut by the slab |z| <= 1: volume pi (r^2 h - h^3/3) * 2 with h = 1.
  const double cap = std::numbers::pi * (2.2 * 2.2 * 1.0 - 1.0 / 3.0) * 2.0;
  EXPECT_NEAR(mesh::EnclosedVolume(carved) / (288.0 - cap), 1.0, 0.01);
}

TEST(Carve, OpenMeshIsInputError) {
  auto plate = testing::BoxMesh({-1, -1, -1}, {1, 1, 1});
  plate.triangles.pop_back();
  EXPECT_THROW(Subtract(plate, testing::BoxMesh({0, 0, 0}, {2, 2, 2})), InputError);
}

}  // namespace
}  // namespace fabatlas::swept
