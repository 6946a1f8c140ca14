// The mesh road (docs/openscad.md, "Two roads"): OpenSCAD's own regression
// models (Debian's openscad-testing-data, written by OpenSCAD's developers)
// evaluated by fabatlas as exact meshes, against OpenSCAD 2021.01's STL of
// the same model: the same volume and the same bounding box. And the exact
// kernel's answers where they are known analytically.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/error.h"
#include "fabatlas/geometry/solid.h"
#include "fabatlas/mesh/enclosed_volume.h"
#include "fabatlas/mesh/exact_boolean.h"
#include "fabatlas/mesh/mesh_report.h"
#include "fabatlas/mesh/read_mesh.h"
#include "fabatlas/scad/primitive_mesh.h"
#include "fabatlas/testing/paths.h"

namespace {

namespace fs = std::filesystem;
namespace design = fabatlas::design;
namespace mesh = fabatlas::mesh;
namespace geometry = fabatlas::geometry;

const fs::path kCorpus = "/usr/share/openscad/testdata/scad/3D";

struct Measured {
  double volume = 0;
  std::array<double, 3> lo{}, hi{};
  std::size_t triangles = 0;
};

Measured Measure(const mesh::TriangleMesh& m) {
  Measured out;
  out.volume = std::abs(mesh::EnclosedVolume(m));
  out.triangles = m.triangles.size();
  if (m.vertices.empty()) return out;
  out.lo = out.hi = m.vertices[0];
  for (const auto& v : m.vertices)
    for (int k = 0; k < 3; ++k) {
      out.lo[k] = std::min(out.lo[k], v[k]);
      out.hi[k] = std::max(out.hi[k], v[k]);
    }
  return out;
}

// OpenSCAD 2021.01's STL of the model: the peer's answer.
Measured Peer(const fs::path& model, const fs::path& dir) {
  const fs::path stl = dir / (model.stem().string() + ".peer.stl");
  const std::string command = "cd '" + model.parent_path().string() + "' && openscad --quiet -o '" + stl.string() +
                              "' '" + model.string() + "' 2>/dev/null";
  EXPECT_EQ(std::system(command.c_str()), 0) << command;
  return Measure(mesh::ReadMesh(stl));
}

// fabatlas's mesh road on the model at its own values (one exposed parameter
// the model does not read).
design::SampleResult Evaluate(const fs::path& model, const fs::path& dir, const std::string& road = "mesh") {
  design::Design d = design::ParseDesign(
      "name: corpus\nvoxel_size: 0.25\nparameters: {unused: {type: integer, min: 0, max: 1, default: 0}}\n"
      "tree: {op: openscad, file: '" +
          model.string() + "', render: " + road + "}\n",
      dir / "corpus.yaml");
  design::EvaluateOptions geometry_only;
  geometry_only.run_checks = false;
  return design::EvaluateSample(d, design::DefaultPoint(d), geometry_only);
}

class CorpusModel : public ::testing::TestWithParam<const char*> {};

TEST_P(CorpusModel, MeshRoadMatchesOpenScadsStl) {
  const fs::path model = kCorpus / GetParam();
  if (!fs::exists(model)) GTEST_SKIP() << "openscad-testing-data is not installed";
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-mesh-road");
  const Measured peer = Peer(model, dir);
  ASSERT_GT(peer.volume, 0) << "OpenSCAD renders " << model << " to nothing";
  const design::SampleResult r = Evaluate(model, dir);
  ASSERT_TRUE(r.valid) << r.failure_reason;
  ASSERT_NE(r.solid.boundary(), nullptr) << "the mesh road gave a level set";
  const Measured ours = Measure(*r.solid.boundary());
  EXPECT_NEAR(ours.volume, peer.volume, 1e-3 * peer.volume) << GetParam();
  EXPECT_NEAR(r.solid.Volume(), peer.volume, 1e-3 * peer.volume) << GetParam();
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(ours.lo[k], peer.lo[k], 1e-3) << GetParam() << " axis " << k;
    EXPECT_NEAR(ours.hi[k], peer.hi[k], 1e-3) << GetParam() << " axis " << k;
  }
  for (const auto& s : r.subtrees) EXPECT_NE(s.op.rfind("csg-levelset:", 0), 0u) << s.op << " fell back to level sets";
}

// Each exercises nodes of the road: primitives and their faceting, booleans
// (coincident faces included), transforms with mirrors, hulls, Minkowski
// sums, resize, extrusions, polyhedra, STL and 3MF imports, surfaces from
// PNG and DAT height maps (a short DAT row, a missing file), 2D objects
// among 3D ones (ignored), boxes meeting along an edge as an operand of a
// further union, a polyhedron OpenSCAD takes as approximately convex.
INSTANTIATE_TEST_SUITE_P(
    Features, CorpusModel,
    ::testing::Values("features/cube-tests.scad", "features/sphere-tests.scad", "features/cylinder-tests.scad",
                      "features/union-tests.scad", "features/union-coincident-test.scad",
                      "features/difference-tests.scad", "features/intersection-tests.scad",
                      "features/mirror-tests.scad", "features/transform-tests.scad", "features/hull3-tests.scad",
                      "features/minkowski3-tests.scad", "features/resize-tests.scad",
                      "features/linear_extrude-tests.scad", "features/rotate_extrude-tests.scad",
                      "features/rotate_extrude-angle.scad", "features/polyhedron-concave-test.scad",
                      "features/import_stl-tests.scad", "features/2d-3d.scad", "features/for-tests.scad",
                      "features/child-tests.scad", "features/minkowski3-erosion.scad", "issues/issue911.scad",
                      "features/surface-png-image3-tests.scad", "features/surface-tests.scad", "issues/issue1223.scad",
                      "features/import_3mf-tests.scad", "features/highlight-modifier2.scad", "issues/issue1867.scad",
                      "features/primitive-inf-tests.scad", "misc/camera-tests.scad"));

// A primitive alone is the sample's solid: its volume is OpenSCAD's, with
// its sign (a sphere's rings run north to south; $fn = inf gives a triangle).
TEST(MeshRoad, LonePrimitivesEncloseOpenScadsVolume) {
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-mesh-road-lone");
  int k = 0;
  for (const char* text : {"sphere(1);", "sphere(2, $fn = 1/0);", "cylinder(r1 = 1, r2 = 0, h = 2);", "cube(2);"}) {
    const fs::path model = dir / ("lone" + std::to_string(++k) + ".scad");
    std::ofstream(model) << text << "\n";
    const Measured peer = Peer(model, dir);
    const design::SampleResult r = Evaluate(model, dir);
    ASSERT_TRUE(r.valid) << text << ": " << r.failure_reason;
    EXPECT_NEAR(r.solid.Volume(), peer.volume, 1e-4 * peer.volume) << text;  // OpenSCAD writes floats
  }
}

// OpenSCAD's own AMF test files (single objects, several volumes, a zipped
// one, one in inches whose unit OpenSCAD ignores) imported by a one-line model.
TEST(MeshRoad, AmfImportsMatchOpenScadsStl) {
  const fs::path amf = "/usr/share/openscad/testdata/amf";
  if (!fs::exists(amf)) GTEST_SKIP() << "openscad-testing-data is not installed";
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-mesh-road-amf");
  for (const char* name :
       {"cube-with-hole", "multi-volume-binary", "sphere20face", "split_pyramid", "tetra_multicolor"}) {
    const fs::path model = dir / (std::string(name) + ".scad");
    std::ofstream(model) << "import(\"" << (amf / (std::string(name) + ".amf")).string() << "\");\n";
    const Measured peer = Peer(model, dir);
    const design::SampleResult r = Evaluate(model, dir);
    ASSERT_TRUE(r.valid) << name << ": " << r.failure_reason;
    EXPECT_NEAR(r.solid.Volume(), peer.volume, 1e-6 * peer.volume) << name;
  }
}

TEST(MeshRoad, SurfaceIsOpenScadsOwnTriangles) {
  // A box with a cylindrical hole: OpenSCAD's STL has a few dozen triangles
  // and every one of its vertices is a vertex of ours (the exact faces of
  // the model), where a level set would carry thousands and round the edges.
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-mesh-road-faces");
  std::ofstream(dir / "box.scad")
      << "difference() { cube([20, 20, 10]); translate([10, 10, -1]) cylinder(r = 5, h = 12, $fn = 24); }\n";
  const Measured peer = Peer(dir / "box.scad", dir);
  const design::SampleResult r = Evaluate(dir / "box.scad", dir);
  ASSERT_TRUE(r.valid) << r.failure_reason;
  const Measured ours = Measure(r.solid.ToMesh());
  EXPECT_NEAR(ours.volume, peer.volume, 1e-5 * peer.volume);  // the STL holds 6 significant digits
  EXPECT_LE(ours.triangles, 2 * peer.triangles);
  const mesh::MeshReport report = mesh::InspectMesh(r.solid.ToMesh());
  EXPECT_TRUE(report.closed && report.manifold && !report.self_intersecting) << report.Reasons();
}

TEST(MeshRoad, TwoDimensionalTrimWithAHugeSquareKeepsTheShapesBox) {
  // The "trim with a huge square" idiom: OpenSCAD's answer is a 20 x 10 x 5
  // slab (the circle's lower half cut away is not there: the square is
  // far larger than the shape). Both roads must give geometry.
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-trim");
  std::ofstream(dir / "trim.scad")
      << "linear_extrude(5) difference() { square([20, 20]); translate([0, 10]) square(4200); }\n";
  const Measured peer = Peer(dir / "trim.scad", dir);
  ASSERT_NEAR(peer.volume, 1000, 1e-6);
  for (const char* road : {"mesh", "levelset"}) {
    const design::SampleResult r = Evaluate(dir / "trim.scad", dir, road);
    ASSERT_TRUE(r.valid) << road << ": " << r.failure_reason;
    EXPECT_NEAR(r.solid.Volume(), peer.volume, road == std::string("mesh") ? 1e-9 : 0.05 * peer.volume) << road;
  }
}

TEST(ExactBoolean, BoxesSharingOnlyAnEdgeGoThroughNefPolyhedra) {
  // Two unit cubes meeting along one edge: corefinement has no manifold
  // result; Nef polyhedra give the union, volume 2 exactly.
  mesh::TriangleMesh a = fabatlas::scad::CubeMesh({1, 1, 1}, false), b = a;
  for (auto& v : b.vertices) v = {v[0] + 1, v[1] + 1, v[2]};
  mesh::BooleanSummary summary;
  const mesh::TriangleMesh u = mesh::ExactBoolean(mesh::BooleanOp::kUnion, {a, b}, &summary);
  EXPECT_DOUBLE_EQ(std::abs(mesh::EnclosedVolume(u)), 2.0);
  EXPECT_EQ(summary.nef, 1);
}

TEST(ExactBoolean, ADifferenceTakesItsOperandsAwayAtOnce) {
  // A 10 x 10 x 1 plate minus three unit holes apart from each other: the
  // holes are joined without an intersection and taken away by one
  // corefinement of the plate (not three); 100 - 3 mm^3.
  const mesh::TriangleMesh plate = fabatlas::scad::CubeMesh({10, 10, 1}, false);
  std::vector<mesh::TriangleMesh> operands{plate};
  for (int i = 0; i < 3; ++i) {
    mesh::TriangleMesh hole = fabatlas::scad::CubeMesh({1, 1, 3}, false);
    for (auto& v : hole.vertices) v = {v[0] + 1 + 3 * i, v[1] + 1, v[2] - 1};
    operands.push_back(hole);
  }
  mesh::BooleanSummary summary;
  const mesh::TriangleMesh d = mesh::ExactBoolean(mesh::BooleanOp::kDifference, operands, &summary);
  EXPECT_NEAR(std::abs(mesh::EnclosedVolume(d)), 97.0, 1e-12);
  EXPECT_EQ(summary.corefinements, 1);
  EXPECT_EQ(summary.nef, 0);
}

TEST(ExactBoolean, DisjointOperandsAreSettledByTheirBoxes) {
  mesh::TriangleMesh a = fabatlas::scad::CubeMesh({1, 1, 1}, false), b = a;
  for (auto& v : b.vertices) v[0] += 3;
  mesh::BooleanSummary summary;
  EXPECT_DOUBLE_EQ(std::abs(mesh::EnclosedVolume(mesh::ExactBoolean(mesh::BooleanOp::kUnion, {a, b}, &summary))), 2.0);
  EXPECT_TRUE(mesh::ExactBoolean(mesh::BooleanOp::kIntersection, {a, b}, &summary).empty());
  EXPECT_DOUBLE_EQ(std::abs(mesh::EnclosedVolume(mesh::ExactBoolean(mesh::BooleanOp::kDifference, {a, b}, &summary))),
                   1.0);
  EXPECT_EQ(summary.corefinements, 0);
}

TEST(MeshSolid, DeltaGIsTheClosedFormAndTheBytesRoundTrip) {
  // Unit cubes shifted by 0.5 along x: |A n B| = 0.5, |A u B| = 1.5, so
  // Delta G = (1.5 - 0.5) / 1.5 = 2/3 (Fab Forms Eq. 2); the columns of
  // the two meshes' Delta G (one voxel apart, off the faces) are exact here.
  geometry::GridSpec grid;
  grid.voxel_size = 0.05;
  mesh::TriangleMesh a = fabatlas::scad::CubeMesh({1, 1, 1}, false), b = a;
  for (auto& v : b.vertices) v[0] += 0.5;
  const geometry::Solid sa = geometry::MeshSolid(grid, a), sb = geometry::MeshSolid(grid, b);
  EXPECT_NEAR(geometry::DeltaG(sa, sb), 2.0 / 3.0, 1e-9);
  EXPECT_EQ(geometry::DeltaG(sa, geometry::MeshSolid(grid, a)), 0.0);  // equal meshes: no change
  EXPECT_NEAR(sa.Volume(), 1.0, 1e-12);
  EXPECT_NEAR(sa.CenterOfMass()[0], 0.5, 1e-12);
  const geometry::Solid back = geometry::Solid::Deserialize(sa.Serialize());
  ASSERT_NE(back.boundary(), nullptr);
  EXPECT_EQ(back.Serialize(), sa.Serialize());
  // The level set built on demand agrees with the mesh to a voxel layer.
  const geometry::Solid voxels = geometry::Intersection(sa, sa);
  EXPECT_EQ(voxels.boundary(), nullptr);
  EXPECT_NEAR(voxels.Volume(), 1.0, 0.05);
}

}  // namespace

namespace {

TEST(MeshRoad, AModelOpenScadRejectsIsBadInputNamingItsLine) {
  // OpenSCAD's parser refuses the model whatever its values: one line with
  // the model, OpenSCAD's line and its message (the CLI exits 2 on it).
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-mesh-road-bad");
  std::ofstream(dir / "bad.scad") << "size = 10;\ncube(size)\nsphere(2;\n";
  try {
    Evaluate(dir / "bad.scad", dir);
    FAIL() << "a model OpenSCAD cannot parse evaluated";
  } catch (const fabatlas::InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find((dir / "bad.scad").string() + ":3: OpenSCAD rejects the model: Parser error"),
              std::string::npos)
        << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

TEST(MeshRoad, ConcavePolyhedronFacesKeepTheirShape) {
  // polyhedron-concave-test.scad's hexagons are concave: OpenSCAD's STL and
  // ours must be the same surface, not only the same volume (a fan of a
  // concave face covers area outside it and cancels it in the volume).
  const fs::path model = kCorpus / "features/polyhedron-concave-test.scad";
  if (!fs::exists(model)) GTEST_SKIP() << "openscad-testing-data is not installed";
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-mesh-road-concave");
  const Measured peer = Peer(model, dir);
  const design::SampleResult r = Evaluate(model, dir);
  ASSERT_TRUE(r.valid) << r.failure_reason;
  double area = 0, peer_area = 0;
  auto area_of = [](const mesh::TriangleMesh& m) {
    double a = 0;
    for (const auto& t : m.triangles) {
      const auto& p = m.vertices[t[0]];
      const auto& q = m.vertices[t[1]];
      const auto& s = m.vertices[t[2]];
      const double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, v[3] = {s[0] - p[0], s[1] - p[1], s[2] - p[2]};
      const double c[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
      a += 0.5 * std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    }
    return a;
  };
  area = area_of(r.solid.ToMesh());
  peer_area = area_of(mesh::ReadMesh(dir / "polyhedron-concave-test.peer.stl"));
  EXPECT_NEAR(area, peer_area, 1e-4 * peer_area);
  EXPECT_NEAR(r.solid.Volume(), peer.volume, 1e-5 * peer.volume);
}

// Delta G of two settings of an OpenSCAD model (the tray at width 60 and 64,
// wall 2 and 2.5: most faces coincide or nearly do): the columns' answer
// against the exact one, from the exact intersection of the two meshes
// (mesh::ExactBoolean), and against the level sets' (the same voxel size).
// Debian's candleStand.scad at count 5 and 6, by hand (its exact
// intersection takes minutes): columns 0.657444, exact 0.65677, level sets
// 0.654614 (docs/openscad.md, "Delta G on the mesh road").
TEST(MeshSolid, DeltaGOfTwoSettingsOfAModelIsTheExactAnswerWithinAVoxel) {
  const fs::path scad = fabatlas::testing::SourceDir() / "configs/scad/tray.scad";
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-mesh-dg");
  design::Design d = design::ParseDesign(
      "name: tray\nvoxel_size: 0.5\nparameters: {width: {type: real, min: 30, max: 120, default: 60},\n"
      "  wall: {type: real, min: 0.4, max: 6, default: 2}}\n"
      "tree: {op: openscad, file: " +
          scad.string() + ", set: {width: width, wall: wall}}\n",
      dir / "tray.yaml");
  design::EvaluateOptions options;
  options.run_checks = false;
  const auto a = design::EvaluateSample(d, design::ParsePoint(d, "width=60,wall=2", "--at"), options);
  const auto b = design::EvaluateSample(d, design::ParsePoint(d, "width=64,wall=2.5", "--at"), options);
  ASSERT_TRUE(a.valid && b.valid) << a.failure_reason << b.failure_reason;
  ASSERT_NE(a.solid.boundary(), nullptr);
  ASSERT_NE(b.solid.boundary(), nullptr);
  const double columns = geometry::DeltaG(a.solid, b.solid);
  const mesh::TriangleMesh& ma = *a.solid.boundary();
  const mesh::TriangleMesh& mb = *b.solid.boundary();
  const double va = mesh::EnclosedVolume(ma), vb = mesh::EnclosedVolume(mb);
  const double vi = mesh::EnclosedVolume(mesh::ExactBoolean(mesh::BooleanOp::kIntersection, {ma, mb}));
  const double exact = (va + vb - 2 * vi) / (va + vb - vi);
  geometry::GridSpec grid;
  grid.voxel_size = 0.5;
  const double level_sets = geometry::DeltaG(geometry::FromMesh(grid, ma), geometry::FromMesh(grid, mb));
  std::cout << "Delta G of the two trays: columns " << columns << ", exact " << exact << ", level sets " << level_sets
            << "\n";
  EXPECT_GT(exact, 0.05);  // the settings differ
  EXPECT_NEAR(columns, exact, 0.003);
  EXPECT_NEAR(level_sets, exact, 0.01);
}

}  // namespace
