// Tests of fabatlas::geometry against analytic volumes, centres and lens
// formulas (no tolerance below is fitted to our own output).
#include "fabatlas/geometry/solid.h"
#include "fabatlas/geometry/convex_mesh_distance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>

#include "fabatlas/error.h"
#include "fabatlas/mesh/enclosed_volume.h"

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
  const fg::GridSpec g = Spec(0.04);  // 50 voxels across each sphere
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

// ---- every primitive against its analytic volume -------------------------------

TEST(GeometrySolid, PrimitiveVolumesWithinOnePercent) {
  const fg::GridSpec g = Spec(0.05);
  struct Case {
    const char* name;
    fg::Solid solid;
    double expected;
  };
  const double n = 6, R = 1.0, h = 2.0;
  const std::vector<Case> cases = {
      {"cylinder", fg::Cylinder(g, 1.0, 2.0), kPi * 1.0 * 2.0},
      {"frustum", fg::Cone(g, 1.0, 0.5, 2.0), kPi * 2.0 / 3.0 * (1.0 + 0.5 + 0.25)},
      {"cone", fg::Cone(g, 1.0, 0.0, 2.0), kPi * 2.0 / 3.0},
      {"torus", fg::Torus(g, 1.0, 0.4), 2 * kPi * kPi * 1.0 * 0.16},
      {"capsule", fg::Capsule(g, {-0.5, 0.2, 0.1}, {0.7, -0.3, 0.4}, 0.5),
       SphereVolume(0.5) + kPi * 0.25 * std::sqrt(1.2 * 1.2 + 0.5 * 0.5 + 0.3 * 0.3)},
      {"extruded square", fg::Extrude(g, {{0, 0}, {1.5, 0}, {1.5, 1.5}, {0, 1.5}}, 1.0), 1.5 * 1.5 * 1.0},
      {"extruded L (clockwise)", fg::Extrude(g, {{0, 0}, {0, 2}, {1, 2}, {1, 1}, {2, 1}, {2, 0}}, 0.8), 3 * 0.8},
      {"smooth revolve = cylinder", fg::Revolve(g, {{0, -1}, {1, -1}, {1, 1}, {0, 1}}, 0), kPi * 2.0},
      {"smooth revolve ring", fg::Revolve(g, {{0.5, 0}, {1, 0}, {1, 1}, {0.5, 1}}, 0), kPi * (1 - 0.25)},
      {"hexagonal revolve = prism", fg::Revolve(g, {{0, 0}, {R, 0}, {R, h}, {0, h}}, 6),
       n / 2 * R * R * std::sin(2 * kPi / n) * h},
      {"square revolve = prism", fg::Revolve(g, {{0, 0}, {R, 0}, {R, h}, {0, h}}, 4), 2 * R * R * h},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    EXPECT_REL_NEAR(c.solid.Volume(), c.expected, 0.01);
  }
}

TEST(GeometrySolid, PrimitiveCentresOfMass) {
  const fg::GridSpec g = Spec(0.05);
  // Cone of height h with its base at z = -h/2: centroid h/4 above the base.
  const fg::Vec3 cone = fg::Cone(g, 1.0, 0.0, 2.0).CenterOfMass();
  EXPECT_NEAR(cone[2], -1.0 + 0.5, 0.01);
  const fg::Vec3 ext = fg::Extrude(g, {{0, 0}, {2, 0}, {2, 1}, {0, 1}}, 3.0).CenterOfMass();
  EXPECT_NEAR(ext[0], 1.0, 0.01);
  EXPECT_NEAR(ext[1], 0.5, 0.01);
  EXPECT_NEAR(ext[2], 1.5, 0.01);
}

// ---- CSG, offsets, arrays, transforms ------------------------------------------

TEST(GeometrySolid, OffsetOfSphereIsLargerAndSmallerSphere) {
  const fg::GridSpec g = Spec(0.05);
  const fg::Solid s = fg::Sphere(g, 1.0);
  EXPECT_REL_NEAR(fg::Offset(s, 0.3).Volume(), SphereVolume(1.3), 0.01);
  EXPECT_REL_NEAR(fg::Offset(s, -0.4).Volume(), SphereVolume(0.6), 0.01);
  EXPECT_TRUE(fg::Offset(s, -1.2).empty());
}

TEST(GeometrySolid, ShellVolume) {
  const fg::Solid s = fg::Sphere(Spec(0.04), 1.0);
  const fg::Solid shell = fg::Shell(s, 0.2);
  EXPECT_REL_NEAR(shell.Volume(), SphereVolume(1.0) - SphereVolume(0.8), 0.01);
  // The hollow shell has no material at the centre.
  EXPECT_REL_NEAR(fg::Intersection(shell, fg::Sphere(Spec(0.04), 0.5)).Volume() + 1.0, 1.0, 1e-3);
}

TEST(GeometrySolid, ArraysOfDisjointCopies) {
  const fg::GridSpec g = Spec(0.05);
  const fg::Solid s = fg::Sphere(g, 0.5);
  const double v = s.Volume();
  const fg::Solid lin = fg::LinearArray(s, 4, {1.5, 0.25, 0});
  EXPECT_REL_NEAR(lin.Volume(), 4 * v, 0.002);
  const fg::Vec3 c = lin.CenterOfMass();
  EXPECT_NEAR(c[0], 1.5 * 1.5, 1e-3);
  EXPECT_NEAR(c[1], 1.5 * 0.25, 1e-3);
  const fg::Solid off_axis = fg::Translate(fg::Sphere(g, 0.4), {1.5, 0, 0});
  const fg::Solid polar = fg::PolarArray(off_axis, 5, 360.0);
  EXPECT_REL_NEAR(polar.Volume(), 5 * SphereVolume(0.4), 0.01);
  const fg::Vec3 pc = polar.CenterOfMass();  // symmetric: centre on the axis
  EXPECT_NEAR(pc[0], 0.0, 5e-3);
  EXPECT_NEAR(pc[1], 0.0, 5e-3);
}

TEST(GeometrySolid, TransformsPreserveVolumeAndMoveCentre) {
  const fg::GridSpec g = Spec(0.05);
  const fg::Solid box = fg::Box(g, {1.0, 0.6, 0.4});
  const double v = box.Volume();
  // Lattice translation is exact.
  const fg::Solid t = fg::Translate(box, {0.5, -1.0, 2.0});
  EXPECT_NEAR(t.Volume(), v, 1e-9 * v);
  const fg::Vec3 c = t.CenterOfMass();
  EXPECT_NEAR(c[0], 0.5, 1e-9);
  EXPECT_NEAR(c[1], -1.0, 1e-9);
  EXPECT_NEAR(c[2], 2.0, 1e-9);
  // Off-lattice translation resamples.
  const fg::Vec3 c2 = fg::Translate(box, {0.123, 0.456, -0.789}).CenterOfMass();
  EXPECT_NEAR(c2[0], 0.123, 0.005);
  EXPECT_NEAR(c2[1], 0.456, 0.005);
  EXPECT_NEAR(c2[2], -0.789, 0.005);
  // Rotation R = Rz*Ry*Rx: the point (1,0,0) goes to (0,1,0) under Rz(90).
  const fg::Solid ball = fg::Translate(fg::Sphere(g, 0.3), {1.0, 0, 0});
  const fg::Vec3 r = fg::Rotate(ball, {0, 0, 90}).CenterOfMass();
  EXPECT_NEAR(r[0], 0.0, 0.005);
  EXPECT_NEAR(r[1], 1.0, 0.005);
  // Rx(90) first takes (0,1,0) to (0,0,1), then Rz(90) leaves it there.
  const fg::Solid ball_y = fg::Translate(fg::Sphere(g, 0.3), {0, 1.0, 0});
  const fg::Vec3 r2 = fg::Rotate(ball_y, {90, 0, 90}).CenterOfMass();
  EXPECT_NEAR(r2[0], 0.0, 0.005);
  EXPECT_NEAR(r2[1], 0.0, 0.005);
  EXPECT_NEAR(r2[2], 1.0, 0.005);
  EXPECT_REL_NEAR(fg::Rotate(box, {20, 30, 40}).Volume(), 0.24, 0.01);
  EXPECT_REL_NEAR(fg::Scale(fg::Sphere(g, 0.5), 2.0).Volume(), SphereVolume(1.0), 0.01);
}

TEST(GeometrySolid, OperationsLeaveInputsUntouched) {
  const fg::GridSpec g = Spec(0.05);
  const fg::Solid a = fg::Sphere(g, 1.0);
  const fg::Solid b = fg::Translate(fg::Sphere(g, 1.0), {0.5, 0, 0});
  const double va = a.Volume(), vb = b.Volume();
  (void)fg::Union(a, b);
  (void)fg::Difference(a, b);
  (void)fg::Intersection(a, b);
  EXPECT_DOUBLE_EQ(a.Volume(), va);
  EXPECT_DOUBLE_EQ(b.Volume(), vb);
}

TEST(GeometrySolid, MixedVoxelSizesAreResampled) {
  const fg::Solid a = fg::Sphere(Spec(0.04), 1.0);
  const fg::Solid b = fg::Translate(fg::Sphere(Spec(0.1), 1.0), {0.5, 0, 0});
  const fg::Solid u = fg::Union(a, b);
  EXPECT_DOUBLE_EQ(u.voxel_size(), 0.04);
  EXPECT_REL_NEAR(u.Volume(), 2 * SphereVolume(1.0) - LensVolume(1.0, 0.5), 0.01);
}

// ---- meshes -------------------------------------------------------------------

namespace {
fabatlas::mesh::TriangleMesh CubeMesh(double s) {
  fabatlas::mesh::TriangleMesh m;
  for (int i = 0; i < 8; ++i) m.vertices.push_back({(i & 1) * s, ((i >> 1) & 1) * s, ((i >> 2) & 1) * s});
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

}  // namespace

TEST(GeometrySolid, FromMeshOfClosedCube) {
  const fg::Solid s = fg::FromMesh(Spec(0.05), CubeMesh(1.5));
  EXPECT_REL_NEAR(s.Volume(), 1.5 * 1.5 * 1.5, 0.01);
  const fg::Vec3 c = s.CenterOfMass();
  for (double v : c) EXPECT_NEAR(v, 0.75, 0.005);
}

// An axis-aligned box's distance in closed form (ConvexMeshDistance's box
// path) against the triangle path of the same box turned by 1e-9 rad about a
// skew axis (the turn moves points by < 1e-7 mm): equal within 1e-6 mm at
// points inside, on and around a 60 x 40 x 15 box moved off the origin, out
// to the band the triangle path is exact in.
TEST(GeometrySolid, ConvexMeshDistanceOfAnAxisAlignedBoxIsTheTrianglePaths) {
  fabatlas::mesh::TriangleMesh box = CubeMesh(1.0);
  for (auto& v : box.vertices) v = {v[0] * 60 + 2, v[1] * 40 - 3, v[2] * 15 + 1};
  fabatlas::mesh::TriangleMesh turned = box;
  const double a = 1e-9, c = std::cos(a), sn = std::sin(a);
  for (auto& v : turned.vertices) {  // about the axis (1, 1, 1) / sqrt(3), Rodrigues
    const double k = 1 / std::sqrt(3.0), t = 1 - c;
    const double x = v[0], y = v[1], z = v[2];
    v = {(t * k * k + c) * x + (t * k * k - sn * k) * y + (t * k * k + sn * k) * z,
         (t * k * k + sn * k) * x + (t * k * k + c) * y + (t * k * k - sn * k) * z,
         (t * k * k - sn * k) * x + (t * k * k + sn * k) * y + (t * k * k + c) * z};
  }
  const double band = 3.0;
  const fg::DistanceFunction closed = fg::ConvexMeshDistance(box, band),
                             triangles = fg::ConvexMeshDistance(turned, band);
  ASSERT_TRUE(closed && triangles);
  int compared = 0;
  for (double x = -1.3; x <= 65; x += 0.7)
    for (double y = -6; y <= 40; y += 0.9)
      for (double z = -2; z <= 19; z += 0.45) {
        const double d = triangles(x, y, z);
        if (d >= band) continue;  // beyond the band the triangle path gives a lower bound only
        EXPECT_NEAR(closed(x, y, z), d, 1e-6) << x << " " << y << " " << z;
        ++compared;
      }
  EXPECT_GT(compared, 10000);
  EXPECT_NEAR(closed(2, -3, 1), 0, 1e-12);                         // a corner
  EXPECT_NEAR(closed(-1, -7, -3), std::sqrt(9 + 16 + 16), 1e-12);  // 3, 4, 4 mm off the corner
  EXPECT_NEAR(closed(32, 17, 8.5), -7.5, 1e-12);                   // the centre: half the 15 mm height inside
}

// A closed convex mesh takes the exact signed-distance path: the regular
// octahedron |x| + |y| + |z| <= 1 (8 faces, volume 4/3) and a cube whose level
// set is the Box primitive's (the same exact distance); a non-convex L prism
// (volume 3) still goes through meshToLevelSet.
TEST(GeometrySolid, FromMeshOfConvexAndNonConvexMeshes) {
  fabatlas::mesh::TriangleMesh octa;
  octa.vertices = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (int sx : {0, 1})
    for (int sy : {2, 3})
      for (int sz : {4, 5}) octa.triangles.push_back({sx, sy, sz});
  const fg::Solid o = fg::FromMesh(Spec(0.02), octa);
  EXPECT_REL_NEAR(o.Volume(), 4.0 / 3.0, 0.01);
  const fg::Box3 box = o.BoundingBox();
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(box.min[k], -1, 0.02);
    EXPECT_NEAR(box.max[k], 1, 0.02);
  }
  fabatlas::mesh::TriangleMesh cube = CubeMesh(2.0);
  for (auto& v : cube.vertices)
    for (double& x : v) x -= 1.0;
  EXPECT_LT(fg::DeltaG(fg::FromMesh(Spec(0.1), cube), fg::Box(Spec(0.1), {2, 2, 2})), 1e-3);

  // L-shaped prism: the unit squares (0..2) x (0..1) and (0..1) x (1..2), 1 high.
  fabatlas::mesh::TriangleMesh l;
  const double pts[6][2] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  for (int z = 0; z < 2; ++z)
    for (const auto& p : pts) l.vertices.push_back({p[0], p[1], static_cast<double>(z)});
  const int caps[4][3] = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 5}};
  for (const auto& t : caps) {
    l.triangles.push_back({t[0], t[2], t[1]});
    l.triangles.push_back({6 + t[0], 6 + t[1], 6 + t[2]});
  }
  for (int i = 0; i < 6; ++i) {
    const int j = (i + 1) % 6;
    l.triangles.push_back({i, j, 6 + j});
    l.triangles.push_back({i, 6 + j, 6 + i});
  }
  EXPECT_REL_NEAR(fg::FromMesh(Spec(0.05), l).Volume(), 3.0, 0.01);
}

TEST(GeometrySolid, ToMeshOfSphereIsClosedAndEnclosesItsVolume) {
  const fg::Solid s = fg::Sphere(Spec(0.05), 1.0);
  const auto m = s.ToMesh();
  ASSERT_FALSE(m.empty());
  // Closed and consistently oriented: every directed edge has its reverse.
  std::map<std::pair<int, int>, int> edges;
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) ++edges[{t[k], t[(k + 1) % 3]}];
  for (const auto& [e, count] : edges) {
    ASSERT_EQ(count, 1);
    ASSERT_EQ(edges.count({e.second, e.first}), 1u);
  }
  EXPECT_REL_NEAR(fabatlas::mesh::EnclosedVolume(m), SphereVolume(1.0), 0.01);  // positive: outward normals
  // The mesh turns back into the same solid.
  EXPECT_NEAR(fg::DeltaG(fg::FromMesh(Spec(0.05), m), s), 0.0, 0.01);
}

// ---- serialization --------------------------------------------------------------

TEST(GeometrySolid, SerializeRoundTripIsExactAndDeterministic) {
  const fg::GridSpec g = Spec(0.05);
  const fg::Solid a = fg::Union(fg::Sphere(g, 1.0), fg::Box(g, {0.5, 0.5, 3.0}));
  const std::string bytes = a.Serialize();
  EXPECT_EQ(bytes, a.Serialize());
  // An independently built equal solid gives the same bytes.
  EXPECT_EQ(bytes, fg::Union(fg::Sphere(g, 1.0), fg::Box(g, {0.5, 0.5, 3.0})).Serialize());
  const fg::Solid b = fg::Solid::Deserialize(bytes);
  EXPECT_DOUBLE_EQ(b.voxel_size(), 0.05);
  EXPECT_DOUBLE_EQ(b.Volume(), a.Volume());
  EXPECT_EQ(b.Serialize(), bytes);
  EXPECT_TRUE(fg::Solid::Deserialize(fg::Solid().Serialize()).empty());
  EXPECT_THROW(fg::Solid::Deserialize("not a grid"), InputError);
  EXPECT_THROW(fg::Solid::Deserialize(bytes.substr(0, bytes.size() / 2)), InputError);
}

// ---- bad input ------------------------------------------------------------------

TEST(GeometrySolid, BadSizesThrowInputError) {
  const fg::GridSpec g = Spec(0.1);
  EXPECT_THROW(fg::Sphere(g, -1.0), InputError);
  EXPECT_THROW(fg::Sphere(g, 0.0), InputError);
  EXPECT_THROW(fg::Sphere(g, std::nan("")), InputError);
  EXPECT_THROW(fg::Box(g, {1, 0, 1}), InputError);
  EXPECT_THROW(fg::Cylinder(g, 1, std::numeric_limits<double>::infinity()), InputError);
  EXPECT_THROW(fg::Cone(g, 0, 0, 1), InputError);
  EXPECT_THROW(fg::Extrude(g, {{0, 0}, {1, 1}}, 1), InputError);
  EXPECT_THROW(fg::Revolve(g, {{-1, 0}, {1, 0}, {1, 1}}, 0), InputError);
  EXPECT_THROW(fg::Revolve(g, {{0, 0}, {1, 0}, {1, 1}}, 2), InputError);
  EXPECT_THROW(fg::Sphere(Spec(0.0), 1.0), InputError);
  EXPECT_THROW(fg::Sphere(Spec(-0.1), 1.0), InputError);
  EXPECT_THROW(fg::Sphere(Spec(std::nan("")), 1.0), InputError);
  fabatlas::mesh::TriangleMesh bad = CubeMesh(1.0);
  bad.triangles.push_back({0, 1, 99});
  EXPECT_THROW(fg::FromMesh(g, bad), InputError);
  EXPECT_THROW(fg::Shell(fg::Sphere(g, 1.0), 0.0), InputError);
}

TEST(GeometrySolid, VoxelCountGuardThrowsBeforeAllocating) {
  fg::GridSpec g = Spec(0.001);
  try {
    fg::Sphere(g, 50.0);  // 100 mm sphere at 1 micron
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("voxel size 0.001 mm"), std::string::npos) << msg;
    EXPECT_NE(msg.find("limit"), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
  fg::GridSpec small = Spec(0.05);
  small.max_active_voxels = 1000;
  EXPECT_THROW(fg::Sphere(small, 1.0), InputError);
  EXPECT_THROW(fg::FromMesh(small, CubeMesh(2.0)), InputError);
}

// ---- minimum feature thickness --------------------------------------------------

TEST(GeometrySolid, OpeningRemovesThinPlateAndKeepsBall) {
  const fg::GridSpec g = Spec(0.05);
  const fg::Solid plate = fg::Box(g, {3.0, 3.0, 0.3});
  EXPECT_GT(fg::OpeningLossFraction(plate, 0.5), 0.95);
  const fg::Solid ball = fg::Sphere(g, 1.0);
  EXPECT_LT(fg::OpeningLossFraction(ball, 0.5), 0.02);
  // A ball on a thin stalk loses the stalk only.
  const fg::Solid stalk = fg::Cylinder(g, 0.1, 2.0);
  const fg::Solid both = fg::Union(ball, fg::Translate(stalk, {0, 0, 1.5}));
  const double stalk_share = (both.Volume() - ball.Volume()) / both.Volume();
  EXPECT_NEAR(fg::OpeningLossFraction(both, 0.5), stalk_share, 0.02);
}
