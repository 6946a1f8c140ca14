// OpenSCAD models evaluated by fabatlas: enum and string values reach
// OpenSCAD quoted (a string's length sets the geometry), and a string
// dropdown changes the geometry.
#include <gtest/gtest.h>

#include <malloc.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>

#include "fabatlas/design/data_files.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/mesh/enclosed_volume.h"
#include "fabatlas/mesh/read_mesh.h"
#include "fabatlas/mesh/write_mesh.h"
#include "fabatlas/scad/import_design.h"
#include "fabatlas/scad/primitive_mesh.h"
#include "fabatlas/scad/region_outline.h"
#include "fabatlas/testing/paths.h"

namespace {

namespace design = fabatlas::design;

design::Design Imported(const std::filesystem::path& model) {
  fabatlas::scad::ImportSummary s = fabatlas::scad::ImportScad(model, {});
  return design::ParseDesign(s.design_yaml, model.parent_path() / (model.stem().string() + ".yaml"));
}

double Volume(const design::Design& d, const std::string& at) {
  design::EvaluateOptions geometry_only;  // the checks are not what these tests are about
  geometry_only.run_checks = false;
  design::SampleResult r = design::EvaluateSample(d, design::ParsePoint(d, at, "--at"), geometry_only);
  EXPECT_TRUE(r.valid) << at << ": " << r.failure_reason;
  return r.solid.Volume();
}

TEST(ScadEval, StringsReachOpenScadQuoted) {
  auto dir = fabatlas::testing::FreshTempDir("scad-quote");
  // The cube's x edge is the string's length: 1 for "a", 12 for the other.
  std::ofstream(dir / "q.scad") << "label = \"a\"; // [\"a\", \"say \\\"hi\\\", ok\"]\ncube([len(label), 10, 10]);\n";
  design::Design d = Imported(dir / "q.scad");
  ASSERT_EQ(d.exposed.size(), 1u);
  EXPECT_NEAR(Volume(d, "label=0"), 100, 3);
  EXPECT_NEAR(Volume(d, "label=1"), 1200, 12);
}

TEST(ScadEval, StringDropdownChangesTheGeometry) {
  const auto tray = fabatlas::testing::SourceDir() / "configs/scad/tray.scad";
  design::Design d = Imported(tray);
  const double round = Volume(d, "shape=round"), square = Volume(d, "shape=square");
  // 3 holes through the 2 mm floor: 6 mm squares against 32-gon circles of
  // diameter 6 mm ($fn = 32), 3 * 2 * (36 - 16 * 9 * sin(2 pi / 32)) mm^3.
  const double expected = 3 * 2 * (36 - 16 * 9 * std::sin(2 * std::numbers::pi / 32));
  EXPECT_NEAR(round - square, expected, 0.2 * expected) << round << " " << square;
}

}  // namespace

namespace {

// Volume of a closed triangle mesh whatever its orientation, mm^3.
double MeshVolume(const fabatlas::mesh::TriangleMesh& m) { return std::abs(fabatlas::mesh::EnclosedVolume(m)); }

TEST(ScadEval, NativeCsgMatchesOpenScadsOwnRenderAndIsCachedPerSubtree) {
  const std::filesystem::path scad = "/usr/share/openscad/examples/Parametric/candleStand.scad";
  if (!std::filesystem::exists(scad)) GTEST_SKIP() << "openscad examples not installed";
  auto dir = fabatlas::testing::FreshTempDir("scad-native");
  // OpenSCAD's own STL of the model at count = 5: the peer's volume.
  const std::string stl = (dir / "peer.stl").string();
  ASSERT_EQ(std::system(("openscad --quiet -o " + stl + " -D count=5 " + scad.string() + " 2>/dev/null").c_str()), 0);
  const double peer = MeshVolume(fabatlas::mesh::ReadMesh(stl));

  design::Design d = design::ParseDesign(
      "name: candles\nvoxel_size: 0.25\nparameters: {count: {type: integer, min: 3, max: 14, default: 7}}\n"
      "tree: {op: openscad, file: " +
          scad.string() + ", set: {count: count}}\nproperties: [volume]\n",
      dir / "candles.yaml");
  design::InMemorySubtreeCache cache;
  design::EvaluateOptions options;
  options.cache = &cache;
  options.run_checks = false;
  design::SampleResult five = design::EvaluateSample(d, design::ParsePoint(d, "count=5", "--at"), options);
  ASSERT_TRUE(five.valid) << five.failure_reason;
  // The volume enclosed by the extracted surface (what an export writes).
  EXPECT_NEAR(MeshVolume(five.solid.ToMesh()), peer, 0.01 * peer);
  int native = 0, rendered = 0;
  for (const auto& s : five.subtrees) {
    native += s.op.rfind("csg:", 0) == 0;
    rendered += s.op.rfind("csg-openscad:", 0) == 0;
  }
  EXPECT_GT(native, 20);
  EXPECT_EQ(rendered, 0);  // cylinders, cubes, a sphere, transforms, booleans, a linear_extrude of circles
  EXPECT_EQ(five.subtrees.back().op, "openscad");
  EXPECT_EQ(five.subtrees.back().children.size(), 1u);

  // count = 6 shares the centre candle and the base ring's subtrees with count = 5.
  design::SampleResult six = design::EvaluateSample(d, design::ParsePoint(d, "count=6", "--at"), options);
  ASSERT_TRUE(six.valid) << six.failure_reason;
  int hits = 0;
  for (const auto& s : six.subtrees) hits += s.from_cache;
  EXPECT_GT(hits, 0);
  EXPECT_GT(MeshVolume(six.solid.ToMesh()), MeshVolume(five.solid.ToMesh()));
}

}  // namespace

namespace {

// sign.scad (Debian's Parametric example): its text goes through OpenSCAD's
// 2D outline (SVG export) and is extruded natively, so no subtree is rendered
// by OpenSCAD, and the volume matches OpenSCAD's own STL within 2%.
TEST(ScadEval, TextIsExtrudedFromOpenScadsOutline) {
  const std::filesystem::path scad = "/usr/share/openscad/examples/Parametric/sign.scad";
  if (!std::filesystem::exists(scad)) GTEST_SKIP() << "openscad examples not installed";
  auto dir = fabatlas::testing::FreshTempDir("scad-sign");
  const std::string stl = (dir / "peer.stl").string();
  ASSERT_EQ(std::system(("openscad --quiet -o " + stl + " " + scad.string() + " 2>/dev/null").c_str()), 0);
  const double peer = MeshVolume(fabatlas::mesh::ReadMesh(stl));
  design::Design d = design::ParseDesign(
      "name: sign\nvoxel_size: 0.6\nparameters: {radius: {type: real, min: 60, max: 200, default: 80}}\n"
      "tree: {op: openscad, file: " +
          scad.string() + ", set: {radius: radius}}\nproperties: [volume]\n",
      dir / "sign.yaml");
  design::EvaluateOptions options;
  options.run_checks = false;
  design::SampleResult r = design::EvaluateSample(d, design::DefaultPoint(d), options);
  ASSERT_TRUE(r.valid) << r.failure_reason;
  for (const auto& s : r.subtrees) EXPECT_NE(s.op.rfind("csg-openscad:", 0), 0u) << s.op;
  EXPECT_NEAR(r.solid.Volume(), peer, 0.02 * peer);
}

}  // namespace

namespace {

// include <> beside the model, use <> found through OPENSCADPATH: the model
// evaluates natively in place, and an on-the-fly job (WriteImportedJob)
// carries both files, so its copy evaluates the same with OPENSCADPATH unset.
// A 10 x 10 x 2 plate and a 4-fragment "cylinder" of radius 2 and height 5
// (a square of diagonal 4: 8 mm^2): 240 mm^3.
TEST(ScadEval, IncludesAndUsesTravelWithTheModel) {
  auto dir = fabatlas::testing::FreshTempDir("scad-include");
  std::filesystem::create_directories(dir / "model/parts");
  std::filesystem::create_directories(dir / "lib");
  std::ofstream(dir / "model/m.scad") << "w = 10; // [5:20]\ninclude <parts/base.scad>\nuse <peg.scad> // a library\n"
                                         "/* use <nothere.scad> */\nbase(w);\npeg();\n";
  std::ofstream(dir / "model/parts/base.scad") << "module base(w) cube([w, 10, 2]);\n";
  std::ofstream(dir / "lib/peg.scad") << "module peg() translate([0, 0, 2]) cylinder(r = 2, h = 5, $fn = 4);\n";
  ::setenv("OPENSCADPATH", (dir / "lib").c_str(), 1);
  design::Design in_place = Imported(dir / "model/m.scad");
  EXPECT_NEAR(Volume(in_place, "w=10"), 240, 0.02 * 240);

  const auto job = fabatlas::scad::WriteImportedJob(dir / "model/m.scad", dir / "job", {});
  EXPECT_TRUE(std::filesystem::exists(dir / "job/parts/base.scad"));
  EXPECT_TRUE(std::filesystem::exists(dir / "job/peg.scad"));
  std::vector<std::string> carried;
  for (const auto& f : design::IndirectDataFiles(in_place.tree, dir / "model")) carried.push_back(f.relative.string());
  EXPECT_EQ(carried, (std::vector<std::string>{"parts/base.scad", "peg.scad"}));
  ::unsetenv("OPENSCADPATH");
  design::Design copy = design::LoadDesign((dir / "job/m.yaml").string());
  EXPECT_NEAR(Volume(copy, "w=10"), 240, 0.02 * 240);
}

}  // namespace

namespace {

// A twisted linear_extrude as OpenSCAD 2021.01 meshes it: the walls follow
// the outline of the whole 2D child (here (A u B) \ C of three rectangles,
// whose outline no single loop has), each side quad split along its shorter
// diagonal (edges on a line through the axis, one on the outline and one on
// the hole, by the twist's sign), the slices from $fa/$fs (OpenSCAD's helix
// rule). For both twist directions fabatlas's mesh encloses the volume of
// OpenSCAD's own STL to 1e-6; extruding each rectangle and combining in 3D,
// or splitting every quad the same way, does not (example009's fan lost
// 10.8% that way).
TEST(ScadEval, TwistedExtrusionIsOpenScadsMesh) {
  namespace scad = fabatlas::scad;
  auto dir = fabatlas::testing::FreshTempDir("scad-twist");
  const double height = 20;
  const std::vector<scad::Loop> loops = {{{0, -2}, {20, -2}, {20, 6}, {0, 6}},
                                         {{4, -5}, {10, -5}, {10, 13}, {4, 13}},
                                         {{12, 0}, {15, 0}, {15, 3}, {12, 3}}};
  auto in = [](const scad::Loop& l, const scad::Point2& p) {
    return p[0] > l[0][0] && p[0] < l[2][0] && p[1] > l[0][1] && p[1] < l[2][1];
  };
  const scad::Region2 region = scad::ResolveRegion(
      loops, [&](const scad::Point2& p) { return (in(loops[0], p) || in(loops[1], p)) && !in(loops[2], p); });
  ASSERT_EQ(region.loops.size(), 2u);  // the cross's outline and the hole
  double r_sqr = 0;
  for (const auto& loop : region.loops)
    for (int i : loop)
      r_sqr = std::max(r_sqr, region.points[i][0] * region.points[i][0] + region.points[i][1] * region.points[i][1]);
  for (const double twist : {-100.0, 100.0}) {
    std::ofstream(dir / "t.scad")
        << "linear_extrude(height = 20, twist = " << twist
        << ") difference() {\n"
           "  union() { translate([0, -2]) square([20, 8]); translate([4, -5]) square([6, 18]); }\n"
           "  translate([12, 0]) square([3, 3]);\n}\n";
    const std::string stl = (dir / "t.stl").string();
    ASSERT_EQ(std::system(("openscad --quiet -o " + stl + " " + (dir / "t.scad").string() + " 2>/dev/null").c_str()),
              0);
    const double peer = MeshVolume(fabatlas::mesh::ReadMesh(stl));
    const int slices = scad::ExtrudeSlices(r_sqr, 0, height, twist, {1, 1}, 0, 2, 12);
    EXPECT_EQ(slices, 9);  // ceil(100 / 12): fewer than the helix's length over $fs
    const double ours = MeshVolume(scad::LinearExtrudeMesh(region, height, false, twist, slices, {1, 1}));
    EXPECT_NEAR(ours, peer, 1e-6 * peer) << "twist " << twist;
    // The area times the height differs (the walls of a twisted mesh bow):
    // the test is not met by a volume-preserving extrusion.
    EXPECT_GT(std::abs(peer - (20 * 8 + 6 * 10 - 9) * height), 0.005 * peer);
  }
}

// Debian's example020 (its spring: 16 polygons twisted 1500 degrees in 80
// slices; a screw and a nut) and example009 (a fan twisted 57.5 degrees)
// through the openscad node: within 1% of OpenSCAD's own STL (they were
// -18.7% and -10.8% when each loop was twisted on its own).
TEST(ScadEval, TwistedExamplesMatchOpenScad) {
  for (const auto& [name, voxel] : {std::pair{"example020", 1.0}, std::pair{"example009", 0.25}}) {
    const std::filesystem::path scad = std::string("/usr/share/openscad/examples/Old/") + name + ".scad";
    if (!std::filesystem::exists(scad)) GTEST_SKIP() << "openscad examples not installed";
    auto dir = fabatlas::testing::FreshTempDir(std::string("scad-") + name);
    const std::string stl = (dir / "peer.stl").string();
    ASSERT_EQ(std::system(("openscad --quiet -o " + stl + " " + scad.string() + " 2>/dev/null").c_str()), 0);
    const double peer = MeshVolume(fabatlas::mesh::ReadMesh(stl));
    design::Design d = design::ParseDesign("name: twisted\nvoxel_size: " + std::to_string(voxel) +
                                               "\nparameters: {unused: {type: real, min: 0, max: 1}}\n"
                                               "tree: {op: openscad, file: " +
                                               scad.string() + "}\nproperties: [volume]\n",
                                           dir / "twisted.yaml");
    design::EvaluateOptions options;
    options.run_checks = false;
    design::SampleResult r = design::EvaluateSample(d, design::DefaultPoint(d), options);
    ASSERT_TRUE(r.valid) << name << ": " << r.failure_reason;
    for (const auto& s : r.subtrees) EXPECT_NE(s.op.rfind("csg-openscad:", 0), 0u) << name << ": " << s.op;
    EXPECT_NEAR(r.solid.Volume(), peer, 0.01 * peer) << name;
  }
}

}  // namespace

namespace {

// rotate_extrude's facets as OpenSCAD 2021.01 places them: a full turn
// starts on -x (a 3-fragment ring has a vertex at 180 degrees, so the half
// x < 0 holds more of it than of a ring with a vertex at 0), and a partial
// turn has trunc(fragments * angle / 360) sectors (7 fragments through 180
// degrees are 3 sectors, whose polygon is 8% smaller than 4 sectors'). Both
// within 1% of OpenSCAD's own STL.
TEST(ScadEval, RotateExtrudeFacetsAsOpenScad) {
  auto dir = fabatlas::testing::FreshTempDir("scad-rotate");
  const std::vector<std::string> models = {
      "intersection() { rotate_extrude($fn = 3) translate([10, 0]) square(2);\n"
      "  translate([-50, -50, -1]) cube([50, 100, 4]); }\n",
      "rotate_extrude(angle = 180, $fn = 7) translate([10, 0]) square(2);\n"};
  for (std::size_t k = 0; k < models.size(); ++k) {
    const auto scad = dir / ("r" + std::to_string(k) + ".scad");
    std::ofstream(scad) << models[k];
    const std::string stl = (dir / "peer.stl").string();
    ASSERT_EQ(std::system(("openscad --quiet -o " + stl + " " + scad.string() + " 2>/dev/null").c_str()), 0);
    const double peer = MeshVolume(fabatlas::mesh::ReadMesh(stl));
    design::Design d = design::ParseDesign(
        "name: rotate\nvoxel_size: 0.1\nparameters: {unused: {type: real, min: 0, max: 1}}\n"
        "tree: {op: openscad, file: " +
            scad.string() + "}\nproperties: [volume]\n",
        dir / "rotate.yaml");
    design::EvaluateOptions options;
    options.run_checks = false;
    design::SampleResult r = design::EvaluateSample(d, design::DefaultPoint(d), options);
    ASSERT_TRUE(r.valid) << models[k] << r.failure_reason;
    EXPECT_NEAR(r.solid.Volume(), peer, 0.01 * peer) << models[k];
  }
}

}  // namespace

namespace {

// Bytes the process's heap holds in use (glibc: small chunks plus mmapped
// blocks), for a growth between two moments of this test.
std::size_t HeapInUse() {
  const struct mallinfo2 m = mallinfo2();
  return m.uordblks + m.hblkhd;
}

// A model importing a fine mesh (a 300-fragment sphere, 89,400 triangles,
// about 2.2 MB in memory) stretched by the exposed `s`: every sample is a
// new subtree key whose computation brings that mesh from outside fabatlas.
design::Design StretchedImport(const std::filesystem::path& dir) {
  fabatlas::mesh::WriteMesh(fabatlas::scad::SphereMesh(10, 300), dir / "ball.stl");
  std::ofstream(dir / "stretched.scad") << "s = 1;\nscale([s, 1, 1]) import(\"ball.stl\");\n";
  return design::ParseDesign(
      "name: stretched\nvoxel_size: 1\nparameters: {s: {type: real, min: 1, max: 2, default: 1}}\n"
      "tree: {op: openscad, file: stretched.scad, set: {s: s}}\n",
      dir / "stretched.yaml");
}

// What evaluation keeps beside a cached subtree (the records of its
// descendants, the meshes that came from outside fabatlas) lives in the
// cache entry and is counted in its budget (Issue: worker memory bounded):
// over 40 distinct samples under an 8 MiB cache the heap grows by about the
// budget, not by the 40 imported meshes (about 90 MB) that process-wide
// side tables kept before.
TEST(ScadEval, SideDataOfCachedSubtreesStaysWithinTheCacheBudget) {
  auto dir = fabatlas::testing::FreshTempDir("scad-side-data");
  design::Design d = StretchedImport(dir);
  constexpr std::size_t kBudget = std::size_t{8} << 20;
  design::InMemorySubtreeCache cache(design::InMemorySubtreeCache::Options{0.0, kBudget});
  design::EvaluateOptions options;
  options.cache = &cache;
  options.run_checks = false;
  options.keep_solid = false;
  auto sample = [&](int i) {
    design::SampleResult r =
        design::EvaluateSample(d, design::ParsePoint(d, "s=" + std::to_string(1 + i / 64.0), "--at"), options);
    ASSERT_TRUE(r.valid) << r.failure_reason;
  };
  sample(0);  // the first sample's one-off allocations (OpenVDB, the model's parse) are not growth
  const std::size_t before = HeapInUse();
  for (int i = 1; i <= 40; ++i) sample(i);
  const std::size_t after = HeapInUse();
  const double grown_mb = (static_cast<double>(after) - static_cast<double>(before)) / (1 << 20);
  std::printf("heap grew %.1f MB over 40 samples; cache %zu entries, %.1f MB\n", grown_mb, cache.entries(),
              static_cast<double>(cache.bytes()) / (1 << 20));
  EXPECT_LE(cache.bytes(), kBudget);
  EXPECT_LT(grown_mb, 24.0);
  std::filesystem::remove_all(dir);
}

// A subtree found in the cache still brings the meshes that entered it from
// outside fabatlas to the watertight check: a polyhedron cube without its
// top face (4 open edges) fails the check in the sample that computes it and
// in the one that finds the whole `openscad` node in the cache.
TEST(ScadEval, ACachedSubtreeStillBringsItsOutsideMeshToTheWatertightCheck) {
  auto dir = fabatlas::testing::FreshTempDir("scad-open-cached");
  std::ofstream(dir / "open.scad") << "w = 10;\npolyhedron(points = [[0,0,0],[w,0,0],[w,w,0],[0,w,0],"
                                      "[0,0,w],[w,0,w],[w,w,w],[0,w,w]],\n"
                                      "  faces = [[0,1,2,3],[4,5,1,0],[5,6,2,1],[6,7,3,2],[7,4,0,3]]);\n";
  design::Design d = design::ParseDesign(
      "name: open\nvoxel_size: 1\nparameters: {w: {type: real, min: 8, max: 12, default: 10}}\n"
      "tree: {op: openscad, file: open.scad, set: {w: w}}\nchecks: [watertight]\n",
      dir / "open.yaml");
  design::InMemorySubtreeCache cache;
  design::EvaluateOptions options;
  options.cache = &cache;
  for (const char* pass : {"computed", "cached"}) {
    design::SampleResult r = design::EvaluateSample(d, design::DefaultPoint(d), options);
    EXPECT_EQ(r.subtrees.back().from_cache, std::string(pass) == "cached");
    EXPECT_EQ(r.failure, design::kNotWatertight) << pass << ": " << r.failure_reason;
    EXPECT_NE(r.failure_reason.find("polyhedron"), std::string::npos) << pass << ": " << r.failure_reason;
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
