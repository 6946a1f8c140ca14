// ShapeDiameter against shapes whose thickness is known analytically.
#include "fabatlas/mesh/shape_diameter.h"

#include <gtest/gtest.h>

#include <cmath>

#include "fabatlas/error.h"
#include "synthetic_meshes.h"

namespace fabatlas::mesh {
namespace {

TEST(ShapeDiameter, TwoMillimetreSlabMeasuresTwo) {
  // 100 x 100 x 2 mm slab, every face a 40 x 40 grid.
  const TriangleMesh slab = testing::GridBox(100, 100, 2, 40);
  ShapeDiameterOptions options;
  options.thin_threshold = 3.0;
  const ShapeDiameterSummary s = ShapeDiameter(slab, options);
  ASSERT_EQ(s.per_face.size(), slab.triangles.size());
  EXPECT_NEAR(s.median, 2.0, 0.05 * 2.0);
  // The large faces of the slab are all thinner than 3 mm. The side walls
  // (4 x 100 x 2 mm^2 out of 20800 mm^2) face the far side wall 100 mm away;
  // their rays that end on the top or bottom (no wall opposite them) do not
  // count, so some side-wall faces get no value, never a large face.
  EXPECT_GT(s.area_fraction_below, 0.95);
  EXPECT_LE(s.min, s.percentile_5);
  EXPECT_LE(s.percentile_5, s.median);
  EXPECT_LE(s.faces_without_value, 4 * 40 * 40 * 2);
  const double nan_area_bound = 4 * 100.0 * 2.0 / 20800.0;
  EXPECT_LT(1.0 - s.area_fraction_below, nan_area_bound + 1e-9);
}

TEST(ShapeDiameter, SphereMeasuresItsDiameter) {
  const TriangleMesh sphere = testing::IcoSphere(10, 4);
  const ShapeDiameterSummary s = ShapeDiameter(sphere, {});
  EXPECT_NEAR(s.median, 20.0, 0.05 * 20.0);
  EXPECT_GT(s.percentile_5, 0.95 * 20.0);
  EXPECT_EQ(s.area_fraction_below, 0.0);  // nothing under 1 mm
  EXPECT_EQ(s.faces_without_value, 0);
}

TEST(ShapeDiameter, CubeFacesMeasureItsEdgeLength) {
  // Per face: the inward ray from the centre of a face crosses the cube.
  const TriangleMesh cube = testing::GridBox(10, 10, 10, 8);
  const ShapeDiameterSummary s = ShapeDiameter(cube, {});
  EXPECT_NEAR(s.median, 10.0, 0.05 * 10.0);
  // Faces by an edge do not read the neighbouring wall (90 degrees away) as
  // the far side of a wall: every face measures the cube across.
  EXPECT_GT(s.min, 0.95 * 10.0);
  ShapeDiameterOptions every_hit;
  every_hit.wall_angle_degrees = 180;  // any face the ray leaves through
  EXPECT_LT(ShapeDiameter(cube, every_hit).min, 5.0);
}

TEST(ShapeDiameter, IsDeterministic) {
  const TriangleMesh sphere = testing::IcoSphere(5, 3);
  const ShapeDiameterSummary a = ShapeDiameter(sphere, {});
  const ShapeDiameterSummary b = ShapeDiameter(sphere, {});
  ASSERT_EQ(a.per_face.size(), b.per_face.size());
  for (std::size_t f = 0; f < a.per_face.size(); ++f) EXPECT_EQ(a.per_face[f], b.per_face[f]);
}

TEST(ShapeDiameter, InvertedMeshHasNoValues) {
  // Normals pointing inward: rays leave the solid, so no face gets a value.
  TriangleMesh sphere = testing::IcoSphere(10, 2);
  for (auto& t : sphere.triangles) std::swap(t[1], t[2]);
  const ShapeDiameterSummary s = ShapeDiameter(sphere, {});
  EXPECT_EQ(s.faces_without_value, static_cast<std::int64_t>(sphere.triangles.size()));
  EXPECT_TRUE(std::isnan(s.median));
}

TEST(ShapeDiameter, RejectsBadOptionsAndIndices) {
  ShapeDiameterOptions bad;
  bad.rays = 0;
  EXPECT_THROW(ShapeDiameter(testing::UnitCube(), bad), InputError);
  bad = {};
  bad.cone_angle_degrees = 180;
  EXPECT_THROW(ShapeDiameter(testing::UnitCube(), bad), InputError);
  bad = {};
  bad.wall_angle_degrees = 0;
  EXPECT_THROW(ShapeDiameter(testing::UnitCube(), bad), InputError);
  TriangleMesh m = testing::UnitCube();
  m.triangles[0][0] = 99;
  EXPECT_THROW(ShapeDiameter(m, {}), InputError);
}

}  // namespace
}  // namespace fabatlas::mesh
