// Tests of fabatlas::geometry against analytic volumes, centres and lens
// formulas (no tolerance below is fitted to our own output).
#include "fabatlas/geometry/solid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>

#include "fabatlas/error.h"

namespace fg = fabatlas::geometry;
using fabatlas::InputError;

namespace {

constexpr double kPi = std::numbers::pi;

fg::GridSpec Spec(double vs) {
  fg::GridSpec g;
  g.voxel_size = vs;
  return g;
}

double SphereVolume(double r) { return 4.0 / 3.0 * kPi * r * r * r; }

// Volume of the lens shared by two balls of radius r whose centres are d apart.
double LensVolume(double r, double d) { return kPi * (4 * r + d) * (2 * r - d) * (2 * r - d) / 12.0; }

#define EXPECT_REL_NEAR(actual, expected, rel) EXPECT_NEAR(actual, expected, std::abs(expected) * (rel))

}  // namespace

TEST(GeometrySolid, SphereVolumeWithinOnePercent) {
  const fg::Solid s = fg::Sphere(Spec(0.05), 1.0);  // 40 voxels across
  EXPECT_FALSE(s.empty());
  EXPECT_REL_NEAR(s.Volume(), SphereVolume(1.0), 0.01);
  const fg::Vec3 c = s.CenterOfMass();
  for (double v : c) EXPECT_NEAR(v, 0.0, 1e-3);
  const fg::Box3 b = s.BoundingBox();
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(b.min[k], -1.0, 0.05);
    EXPECT_NEAR(b.max[k], 1.0, 0.05);
  }
}

TEST(GeometrySolid, BoxVolumeWithinOnePercent) {
  const fg::Solid s = fg::Box(Spec(0.1), {2.0, 3.0, 4.0});
  EXPECT_REL_NEAR(s.Volume(), 24.0, 0.01);
  const fg::Box3 b = s.BoundingBox();
  EXPECT_NEAR(b.min[0], -1.0, 0.02);
  EXPECT_NEAR(b.max[2], 2.0, 0.02);
}

TEST(GeometrySolid, DeltaGOfUnitSpheresHalfApartMatchesLensFormula) {
  // 80 voxels across each sphere: the crease where the two spheres meet costs
  // about (voxel size)^2 x crease length of volume (second order; 1% at 50).
  const fg::GridSpec g = Spec(0.025);
  const fg::Solid a = fg::Sphere(g, 1.0);
  const fg::Solid b = fg::Translate(fg::Sphere(g, 1.0), {0.5, 0, 0});
  const double lens = LensVolume(1.0, 0.5);
  const double uni = 2 * SphereVolume(1.0) - lens;
  const double expected = (uni - lens) / uni;
  EXPECT_NEAR(expected, 0.53712, 5e-5);  // the number is the lens formula
  EXPECT_REL_NEAR(fg::DeltaG(a, b), 0.53712, 0.01);
  EXPECT_REL_NEAR(fg::Intersection(a, b).Volume(), lens, 0.01);
  EXPECT_REL_NEAR(fg::Union(a, b).Volume(), uni, 0.01);
  EXPECT_REL_NEAR(fg::Difference(a, b).Volume(), SphereVolume(1.0) - lens, 0.01);
}

TEST(GeometrySolid, DeltaGConventions) {
  const fg::Solid a = fg::Sphere(Spec(0.1), 1.0);
  EXPECT_DOUBLE_EQ(fg::DeltaG(a, a), 0.0);
  EXPECT_DOUBLE_EQ(fg::DeltaG(fg::Solid(), fg::Solid()), 0.0);
  EXPECT_DOUBLE_EQ(fg::DeltaG(a, fg::Solid()), 1.0);
  EXPECT_DOUBLE_EQ(fg::DeltaG(fg::Solid(), a), 1.0);
  // Disjoint solids share nothing.
  const fg::Solid far = fg::Translate(a, {5, 0, 0});
  EXPECT_NEAR(fg::DeltaG(a, far), 1.0, 1e-9);
}
