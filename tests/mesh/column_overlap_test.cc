// mesh::IntegrateColumnOverlap against closed forms: boxes (exact on a grid
// offset from their faces), coaxial prisms (the n-gon's area n/2 r^2
// sin(2 pi / n) times the heights' overlap), an icosphere against its own
// exact volume, overlapping shells of one mesh counted once.
#include "fabatlas/mesh/column_overlap.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "fabatlas/error.h"
#include "fabatlas/mesh/enclosed_volume.h"
#include "synthetic_meshes.h"

namespace {

using fabatlas::mesh::IntegrateColumnOverlap;
using fabatlas::mesh::TriangleMesh;
namespace t = fabatlas::mesh::testing;

// A closed prism over the regular n-gon of circumradius r about the z axis,
// from z0 to z1, outward triangles (as OpenSCAD facets a cylinder).
TriangleMesh Prism(int n, double r, double z0, double z1) {
  TriangleMesh m;
  for (double z : {z0, z1})
    for (int i = 0; i < n; ++i) {
      const double a = 2 * std::numbers::pi * i / n;
      m.vertices.push_back({r * std::cos(a), r * std::sin(a), z});
    }
  m.vertices.push_back({0, 0, z0});
  m.vertices.push_back({0, 0, z1});
  const int bottom = 2 * n, top = 2 * n + 1;
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    m.triangles.push_back({bottom, j, i});
    m.triangles.push_back({top, n + i, n + j});
    m.triangles.push_back({i, j, n + j});
    m.triangles.push_back({i, n + j, n + i});
  }
  return m;
}

double PolygonArea(int n, double r) { return n / 2.0 * r * r * std::sin(2 * std::numbers::pi / n); }

TEST(ColumnOverlap, ShiftedBoxesAreExact) {
  // |A| = |B| = 1000, |A n B| = 7 * 8 * 9 = 504 (Fab Forms Eq. 2: Delta G = 992 / 1496).
  const auto c = IntegrateColumnOverlap(t::Box(0, 0, 0, 10, 10, 10), t::Box(3, 2, 1, 13, 12, 11), 0.5);
  EXPECT_NEAR(c.volume_a, 1000, 1e-9);
  EXPECT_NEAR(c.volume_b, 1000, 1e-9);
  EXPECT_NEAR(c.volume_both, 504, 1e-9);
  EXPECT_GT(c.columns, 0);
  const auto apart = IntegrateColumnOverlap(t::Box(0, 0, 0, 1, 1, 1), t::Box(5, 0, 0, 6, 1, 1), 0.1);
  EXPECT_NEAR(apart.volume_both, 0, 1e-12);
}

TEST(ColumnOverlap, CoaxialPrismsMatchTheirClosedForms) {
  const int n = 64;
  const TriangleMesh a = Prism(n, 10, 0, 20), b = Prism(n, 6, 5, 35);
  const double va = PolygonArea(n, 10) * 20, vb = PolygonArea(n, 6) * 30, vab = PolygonArea(n, 6) * 15;
  for (double spacing : {0.5, 0.2}) {
    const auto c = IntegrateColumnOverlap(a, b, spacing);
    EXPECT_NEAR(c.volume_a, va, 0.005 * va) << spacing;
    EXPECT_NEAR(c.volume_b, vb, 0.005 * vb) << spacing;
    EXPECT_NEAR(c.volume_both, vab, 0.005 * vab) << spacing;
  }
}

TEST(ColumnOverlap, SphereVolumeAndOverlappingShellsCountedOnce) {
  const TriangleMesh s = t::IcoSphere(5, 4);
  const double exact = fabatlas::mesh::EnclosedVolume(s);
  const auto c = IntegrateColumnOverlap(s, s, 0.1);
  EXPECT_NEAR(c.volume_a, exact, 0.005 * exact);
  EXPECT_NEAR(c.volume_both, c.volume_a, 1e-9);
  // Two overlapping boxes in one mesh: their union, 2 * 8 - 4 = 12.
  const TriangleMesh two = t::Concatenate(t::Box(0, 0, 0, 2, 2, 2), t::Box(1, 0, 0, 3, 2, 2));
  EXPECT_NEAR(IntegrateColumnOverlap(two, t::Box(0, 0, 0, 1, 1, 1), 0.25).volume_a, 12, 1e-9);
}

TEST(ColumnOverlap, ASpacingThatIsNotPositiveIsAnInputError) {
  EXPECT_THROW(IntegrateColumnOverlap(t::UnitCube(), t::UnitCube(), 0), fabatlas::InputError);
  EXPECT_THROW(IntegrateColumnOverlap(t::UnitCube(), t::UnitCube(), -1), fabatlas::InputError);
  EXPECT_THROW(IntegrateColumnOverlap(t::UnitCube(), t::Box(0, 0, 0, 1e4, 1e4, 1), 1e-4), fabatlas::InputError);
}

}  // namespace
