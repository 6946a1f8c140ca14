// OpenSCAD 2021.01's 2-D subtrees and extrusions evaluated natively
// (scad/evaluate_2d.h) against OpenSCAD 2021.01 itself: its SVG export of a
// 2-D model (area, vertices) and its STL of an extrusion (enclosed volume),
// on Debian's openscad-testing-data corpus and on the odd-input idioms.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <numbers>
#include <sstream>

#include "fabatlas/error.h"
#include "fabatlas/mesh/enclosed_volume.h"
#include "fabatlas/mesh/mesh_report.h"
#include "fabatlas/mesh/read_mesh.h"
#include "fabatlas/scad/csg_tree.h"
#include "fabatlas/scad/evaluate_2d.h"
#include "fabatlas/scad/svg_outline.h"
#include "fabatlas/testing/paths.h"

namespace {

namespace fs = std::filesystem;
using fabatlas::mesh::TriangleMesh;
using fabatlas::scad::CsgNode;
using fabatlas::scad::Loop;
using fabatlas::scad::Point2;

const fs::path kCorpus = "/usr/share/openscad/testdata/scad";

std::string ReadText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs OpenSCAD on `model` writing `out` (its extension picks the format);
// returns its stderr. OpenSCAD fails, writing nothing, for an empty result.
std::string RunPeer(const fs::path& model, const fs::path& out) {
  const fs::path log = out.string() + ".log";
  const std::string cmd = "openscad -o '" + out.string() + "' '" + model.string() + "' 2> '" + log.string() + "'";
  const int status = std::system(cmd.c_str());
  const std::string text = ReadText(log);
  if (status != 0) {
    EXPECT_NE(text.find("Current top level object is empty."), std::string::npos) << cmd << "\n" << text;
  }
  return text;
}

CsgNode CsgOf(const fs::path& model, const fs::path& dir) {
  const fs::path csg = dir / (model.stem().string() + ".csg");
  RunPeer(model, csg);
  return fabatlas::scad::ParseCsg(ReadText(csg), csg.string());
}

fs::path Program(const fs::path& dir, const std::string& name, const std::string& text) {
  const fs::path p = dir / name;
  std::ofstream(p) << text << "\n";
  return p;
}

double SignedArea(const std::vector<Loop>& loops) {
  double a = 0;
  for (const Loop& l : loops)
    for (std::size_t i = 0; i < l.size(); ++i) {
      const Point2& p = l[i];
      const Point2& q = l[(i + 1) % l.size()];
      a += 0.5 * (p[0] * q[1] - q[0] * p[1]);
    }
  return a;
}

// The largest distance from a vertex of either side to the nearest vertex
// of the other (mm): 0 when both have the same vertices.
double VertexDistance(const std::vector<Loop>& a, const std::vector<Loop>& b) {
  auto one_way = [](const std::vector<Loop>& x, const std::vector<Loop>& y) {
    double worst = 0;
    for (const Loop& lx : x)
      for (const Point2& p : lx) {
        double best = HUGE_VAL;
        for (const Loop& ly : y)
          for (const Point2& q : ly) best = std::min(best, std::hypot(p[0] - q[0], p[1] - q[1]));
        worst = std::max(worst, best);
      }
    return worst;
  };
  return std::max(one_way(a, b), one_way(b, a));
}

std::size_t Vertices(const std::vector<Loop>& loops) {
  std::size_t n = 0;
  for (const Loop& l : loops) n += l.size();
  return n;
}

// What the exact 3-D booleans need of an operand: closed, manifold, not
// self-intersecting, outward (mesh_report.h, CGAL's tests); an empty mesh
// (an empty extrusion) passes. Returns the failed properties' reasons.
std::string SolidDefects(const TriangleMesh& m) {
  if (m.empty()) return "";
  const fabatlas::mesh::MeshReport r = fabatlas::mesh::InspectMesh(m);
  std::string defects = r.Reasons();
  if (r.degenerate_triangles) defects += "; " + std::to_string(r.degenerate_triangles) + " degenerate triangles";
  return defects;
}

// The options a test gives: 3-D children and outlines from OpenSCAD itself
// (the peer's STL of the child, its SVG of the node), in `dir`.
fabatlas::scad::Evaluate2dOptions PeerOptions(const fs::path& model_dir, const fs::path& dir) {
  fabatlas::scad::Evaluate2dOptions o;
  o.model_dir = model_dir;
  auto counter = std::make_shared<int>(0);
  o.mesh3d = [dir, counter](const CsgNode& child) {
    const fs::path p = Program(dir, "child-" + std::to_string(++*counter) + ".scad", child.canonical);
    const fs::path stl = p.string() + ".stl";
    RunPeer(p, stl);
    return fabatlas::mesh::ReadMesh(stl);
  };
  o.outline = [dir, counter](const CsgNode& node) {
    const fs::path p = Program(dir, "outline-" + std::to_string(++*counter) + ".scad", node.canonical);
    const fs::path svg = p.string() + ".svg";
    RunPeer(p, svg);
    return fs::exists(svg) ? fabatlas::scad::ReadSvgOutline(ReadText(svg), svg.string()) : std::vector<Loop>{};
  };
  return o;
}

struct Compared {
  double ours_area = 0, peer_area = 0, vertex_distance = 0;
  std::size_t ours_vertices = 0, peer_vertices = 0;
  std::vector<std::string> warnings;
  std::string peer_log;
};

// A 2-D model through both: OpenSCAD's SVG export against Evaluate2d of its
// CSG tree.
// `work`: where the CSG export, the peer's files and outline programs go
// (a fresh directory unless given; the model's own for relative imports).
Compared Compare2d(const fs::path& model, const fs::path& work = {}) {
  const fs::path dir = work.empty() ? fabatlas::testing::FreshTempDir("scad-2d") : work;
  const CsgNode root = CsgOf(model, dir);
  // The peer reads the same CSG text we do (the .csg export rounds numbers
  // to 6 digits, 4/3 becoming 1.33333).
  const fs::path csg = dir / (model.stem().string() + ".csg");
  const fs::path svg = dir / (model.stem().string() + ".svg");
  Compared c;
  c.peer_log = RunPeer(csg, svg);
  const std::vector<Loop> peer =
      fs::exists(svg) ? fabatlas::scad::ReadSvgOutline(ReadText(svg), svg.string()) : std::vector<Loop>{};
  const fabatlas::scad::Evaluate2dOptions o = PeerOptions(model.parent_path(), dir);
  const fabatlas::scad::Polygon2d ours = fabatlas::scad::Evaluate2d(root, o, &c.warnings);
  c.ours_area = SignedArea(ours.loops);
  c.peer_area = std::abs(SignedArea(peer));  // SVG's y points down: loops come back in OpenSCAD's sense
  c.vertex_distance = VertexDistance(ours.loops, peer);
  c.ours_vertices = Vertices(ours.loops);
  c.peer_vertices = Vertices(peer);
  return c;
}

// OpenSCAD writes 6 significant digits to SVG: areas agree to ~1e-6
// relative, vertices to 1e-4 mm on these models.
void ExpectSame2d(const fs::path& model, const fs::path& work = {}) {
  SCOPED_TRACE(model.string());
  const Compared c = Compare2d(model, work);
  EXPECT_NEAR(c.ours_area, c.peer_area, 1e-5 * std::max(1.0, c.peer_area));
  EXPECT_LT(c.vertex_distance, 1e-3);
  EXPECT_EQ(c.ours_vertices, c.peer_vertices);
  std::printf("%-34s area ours %.6f peer %.6f (rel %.1e), vertices %zu / %zu, vertex distance %.2e mm\n",
              model.filename().c_str(), c.ours_area, c.peer_area,
              std::abs(c.ours_area - c.peer_area) / std::max(1.0, c.peer_area), c.ours_vertices, c.peer_vertices,
              c.vertex_distance);
}

TEST(Scad2d, CorpusBooleansMatchOpenScad) {
  if (!fs::exists(kCorpus)) GTEST_SKIP() << "openscad-testing-data not installed";
  for (const char* f :
       {"difference-2d-tests.scad", "intersection2-tests.scad", "polygon-tests.scad", "polygons-touch.scad",
        "square-tests.scad", "circle-tests.scad", "scale2D-tests.scad", "render-2d-tests.scad", "nullspace-2d.scad",
        "control-hull-dimension.scad", "highlight-modifier-2d.scad"})
    ExpectSame2d(kCorpus / "2D/features" / f);
}

TEST(Scad2d, CorpusOffsetHullMinkowskiResizeMatchOpenScad) {
  if (!fs::exists(kCorpus)) GTEST_SKIP() << "openscad-testing-data not installed";
  for (const char* f : {"offset-tests.scad", "hull2-tests.scad", "minkowski2-tests.scad", "minkowski2-hole-tests.scad",
                        "minkowski2-crack.scad", "resize-2d-tests.scad"})
    ExpectSame2d(kCorpus / "2D/features" / f);
}

TEST(Scad2d, CorpusProjectionsMatchOpenScad) {
  if (!fs::exists(kCorpus)) GTEST_SKIP() << "openscad-testing-data not installed";
  for (const char* f : {"projection-tests.scad", "projection-cut-tests.scad"})
    ExpectSame2d(kCorpus / "2D/features" / f);
}

// A 3-D child under a 2-D operation is ignored, with OpenSCAD's warning.
TEST(Scad2d, ThreeDimensionalChildIsIgnoredWithOpenScadsWarning) {
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-2d-mixed");
  const fs::path model = Program(dir, "mixed.scad",
                                 "difference() { square(10); cube(4); }\n"
                                 "translate([20, 0]) offset(1) { circle(3); sphere(2); }");
  const Compared c = Compare2d(model);
  EXPECT_NEAR(c.ours_area, c.peer_area, 1e-5 * c.peer_area);
  // The cube cut nothing; the sphere added nothing to the offset circle.
  EXPECT_GT(c.peer_area, 100 + 0.9 * std::numbers::pi * 16);
  EXPECT_LT(c.peer_area, 100 + std::numbers::pi * 16);
  int ours = 0;
  for (const auto& w : c.warnings) ours += w.find("Ignoring 3D child object for 2D operation") != std::string::npos;
  EXPECT_EQ(ours, 2);
  EXPECT_NE(c.peer_log.find("Ignoring 3D child object for 2D operation"), std::string::npos) << c.peer_log;
}

// A polygon with an infinite coordinate is empty (OpenSCAD's error line); a
// NaN coordinate drops its point here, with a warning.
TEST(Scad2d, NonFinitePoints) {
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-2d-nonfinite");
  const fs::path model = Program(dir, "inf.scad", "polygon([[0, 0], [10, 0], [1/0, 5], [0, 10]]);\nsquare(3);");
  const Compared c = Compare2d(model);
  EXPECT_NEAR(c.ours_area, 9, 1e-12);
  EXPECT_NEAR(c.peer_area, 9, 1e-9);
  bool said = false;
  for (const auto& w : c.warnings) said |= w.find("Unable to convert points[2] = [inf, 5]") != std::string::npos;
  EXPECT_TRUE(said);

  // NaN: OpenSCAD hands Clipper an undefined integer, so there is no peer
  // answer; the point is dropped.
  CsgNode nan_polygon =
      fabatlas::scad::ParseCsg("polygon(points = [[0, 0], [10, 0], [nan, 5], [10, 10], [0, 10]]);", "nan.csg");
  std::vector<std::string> warnings;
  const auto p = fabatlas::scad::Evaluate2d(nan_polygon, {}, &warnings);
  EXPECT_NEAR(SignedArea(p.loops), 100, 1e-9);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("points[2]"), std::string::npos) << warnings[0];
}

// Trimming with a huge square, a common idiom; offsets of every kind.
TEST(Scad2d, TrimAndOffsetIdioms) {
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-2d-idioms");
  ExpectSame2d(Program(dir, "trim.scad",
                       "difference() { circle(r = 30, $fn = 67); translate([-4200, -4200]) square(4200); }\n"
                       "translate([80, 0]) intersection() { circle(20); square(4200, center = true); }"));
  ExpectSame2d(Program(dir, "offsets.scad",
                       "module s() { difference() { square([30, 20]); translate([10, 5]) square([10, 10]); } }\n"
                       "offset(r = 2.5) s();\n"
                       "translate([50, 0]) offset(r = -2, $fn = 24) s();\n"
                       "translate([100, 0]) offset(delta = 3) rotate(17) s();\n"
                       "translate([150, 0]) offset(delta = 3, chamfer = true) rotate(17) s();\n"
                       "translate([0, 50]) offset(r = 4, $fa = 5, $fs = 0.5) polygon([[0,0],[20,0],[2,3],[0,20]]);\n"
                       "translate([50, 50]) offset(delta = -1) polygon([[0,0],[20,0],[2,3],[0,20]]);\n"
                       "translate([100, 50]) mirror([1, 0]) offset(r = 1) square(5);"));
}

TEST(Scad2d, ImportIsResolvedBelowTheModelAndRefusedOutside) {
  const fs::path dxf = kCorpus / "../dxf/polygons.dxf";
  if (!fs::exists(dxf)) GTEST_SKIP() << "openscad-testing-data not installed";
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-2d-import");
  fs::copy_file(dxf, dir / "polygons.dxf");
  ExpectSame2d(
      Program(dir, "imp.scad", "import(\"polygons.dxf\"); translate([0, 200]) offset(1) import(\"polygons.dxf\");"),
      dir);
  CsgNode outside = fabatlas::scad::ParseCsg("import(file = \"../../etc/passwd.svg\");", "outside.csg");
  fabatlas::scad::Evaluate2dOptions o = PeerOptions(dir, dir);
  EXPECT_THROW(fabatlas::scad::Evaluate2d(outside, o, nullptr), fabatlas::InputError);
}

// text through the outline callback (OpenSCAD's own SVG of the text node,
// here with the fonts OpenSCAD finds when it reads the .csg).
TEST(Scad2d, CorpusTextThroughItsOutline) {
  if (!fs::exists(kCorpus)) GTEST_SKIP() << "openscad-testing-data not installed";
  ExpectSame2d(kCorpus / "2D/features/text-font-simple-tests.scad");
}

TEST(Scad2d, TextWithoutOutlineHasNoNativeEquivalent) {
  CsgNode text = fabatlas::scad::ParseCsg("text(text = \"a\", size = 10);", "text.csg");
  EXPECT_THROW(fabatlas::scad::Evaluate2d(text, {}, nullptr), fabatlas::scad::NoNativeEquivalentError);
  EXPECT_EQ(fabatlas::scad::Dimension(text), 2);
}

// ---- Extrusions -------------------------------------------------------

using Affine = std::array<double, 12>;  // rows of a 3x4 matrix

// A corpus subtree: a chain of single-child multmatrix / group / color
// nodes ending in an extrusion, as our mesh in the subtree's coordinates.
// Empty optional when the subtree is something else.
std::optional<TriangleMesh> ExtrusionChain(const CsgNode& n, const fabatlas::scad::Evaluate2dOptions& o,
                                           std::vector<std::string>* warnings) {
  if (n.name == "linear_extrude") return fabatlas::scad::LinearExtrude(n, o, warnings);
  if (n.name == "rotate_extrude") return fabatlas::scad::RotateExtrude(n, o, warnings);
  if (n.children.size() != 1) return std::nullopt;
  if (n.name == "group" || n.name == "color" || n.name == "render") return ExtrusionChain(n.children[0], o, warnings);
  if (n.name != "multmatrix") return std::nullopt;
  std::optional<TriangleMesh> m = ExtrusionChain(n.children[0], o, warnings);
  if (!m) return m;
  const auto& rows = (n.args.count("m") ? n.args.at("m") : n.positional.at(0)).items;  // the .csg writes it unnamed
  for (auto& v : m->vertices) {
    std::array<double, 3> w{};
    for (int r = 0; r < 3; ++r)
      w[r] = rows[r].items[0].number * v[0] + rows[r].items[1].number * v[1] + rows[r].items[2].number * v[2] +
             rows[r].items[3].number;
    v = w;
  }
  return m;
}

struct Solid {
  std::string subtree;
  double ours = 0, peer = 0;
  std::string defects;  // SolidDefects of our mesh
};

// Every top-level extrusion of a corpus model: our mesh's volume against
// that of OpenSCAD's STL of the same subtree alone.
std::vector<Solid> CompareExtrusions(const fs::path& model) {
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-extrude");
  const CsgNode root = CsgOf(model, dir);
  const fabatlas::scad::Evaluate2dOptions o = PeerOptions(model.parent_path(), dir);
  std::vector<Solid> out;
  int k = 0;
  std::function<void(const CsgNode&)> visit = [&](const CsgNode& c) {
    std::vector<std::string> warnings;
    std::optional<TriangleMesh> ours = ExtrusionChain(c, o, &warnings);
    if (!ours) {
      // Several children (a for loop's, a module's): each a program of its
      // own, compared in its own coordinates.
      if (c.name == "group" || c.name == "multmatrix" || c.name == "color" || c.name == "render")
        for (const CsgNode& g : c.children) visit(g);
      return;
    }
    Solid s;
    s.subtree = c.canonical.substr(0, 160);
    s.ours = fabatlas::mesh::EnclosedVolume(*ours);
    s.defects = SolidDefects(*ours);
    const fs::path p = Program(dir, "subtree-" + std::to_string(++k) + ".scad", c.canonical);
    const fs::path stl = p.string() + ".stl";
    const std::string cmd = "openscad -o '" + stl.string() + "' '" + p.string() + "' 2>/dev/null";
    if (std::system(cmd.c_str()) == 0 && fs::exists(stl))
      s.peer = std::abs(fabatlas::mesh::EnclosedVolume(fabatlas::mesh::ReadMesh(stl)));
    out.push_back(s);
  };
  for (const CsgNode& c : root.children) visit(c);
  return out;
}

// OpenSCAD writes 6 significant digits to STL: volumes agree to ~1e-5.
// `sound_at_least`: the solids that must be fit for the exact booleans
// (SolidDefects empty): all unless given (a top scaled to zero where loops
// collapse onto one segment or point is not, as OpenSCAD's is not).
void ExpectSameSolids(const fs::path& model, std::size_t at_least, std::size_t sound_at_least = SIZE_MAX) {
  SCOPED_TRACE(model.string());
  const std::vector<Solid> solids = CompareExtrusions(model);
  EXPECT_GE(solids.size(), at_least);
  std::size_t sound = 0;
  for (const Solid& s : solids) {
    sound += s.defects.empty();
    if (sound_at_least == SIZE_MAX) {
      EXPECT_EQ(s.defects, "") << s.subtree;
    }
  }
  EXPECT_GE(sound, std::min(sound_at_least, solids.size()));
  for (const Solid& s : solids) {
    EXPECT_NEAR(s.ours, s.peer, 2e-5 * std::max(1.0, s.peer)) << s.subtree;
    std::printf("%-40s volume ours %.5f peer %.5f (rel %.1e)  %s%s\n", model.filename().c_str(), s.ours, s.peer,
                std::abs(s.ours - s.peer) / std::max(1.0, s.peer), s.subtree.substr(0, 70).c_str(),
                s.defects.empty() ? "" : ("\n    " + s.defects).c_str());
  }
}

TEST(Scad2d, CorpusLinearExtrudesMatchOpenScad) {
  if (!fs::exists(kCorpus)) GTEST_SKIP() << "openscad-testing-data not installed";
  ExpectSameSolids(kCorpus / "3D/features/linear_extrude-tests.scad", 14);
  ExpectSameSolids(kCorpus / "3D/features/linear_extrude-parameter-tests.scad", 48);
  // 24 solids; 12 have two loops (a hole, two squares) whose top scaled to
  // zero collapses onto one segment or one point, where OpenSCAD's solid is
  // not a 2-manifold either.
  ExpectSameSolids(kCorpus / "3D/features/linear_extrude-scale-zero-tests.scad", 24, 12);
}

TEST(Scad2d, CorpusRotateExtrudesMatchOpenScad) {
  if (!fs::exists(kCorpus)) GTEST_SKIP() << "openscad-testing-data not installed";
  ExpectSameSolids(kCorpus / "3D/features/rotate_extrude-tests.scad", 6);
  ExpectSameSolids(kCorpus / "3D/features/rotate_extrude-angle.scad", 17);
}

TEST(Scad2d, DebianExampleExtrusionsMatchOpenScad) {
  const fs::path examples = "/usr/share/openscad/examples";
  if (!fs::exists(examples)) GTEST_SKIP() << "openscad examples not installed";
  ExpectSameSolids(examples / "Basics/linear_extrude.scad", 4);
  ExpectSameSolids(examples / "Advanced/offset.scad", 2);
  ExpectSameSolids(examples / "Old/example017.scad", 5);
  ExpectSameSolids(examples / "Old/example020.scad", 2);  // a spring twisted 1500 degrees in 80 slices
}

TEST(Scad2d, ExtrusionIdiomsMatchOpenScad) {
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-extrude-idioms");
  ExpectSameSolids(
      Program(dir, "idioms.scad",
              "rotate_extrude(angle = 90, $fn = 40) translate([10, 0]) difference() { circle(4); circle(2); }\n"
              "rotate_extrude(angle = -200) translate([5, 0]) square([3, 8]);\n"
              "rotate_extrude($fn = 7) polygon([[0, 0], [6, 0], [2, 5], [0, 9]]);\n"
              "linear_extrude(height = 12, twist = 90, scale = [0.5, 1.5]) difference() { square(10, center = true); "
              "circle(3); }\n"
              "linear_extrude(height = 5, scale = 0) circle(4);\n"
              "linear_extrude(height = 7, twist = -130, scale = 0.3, center = true) translate([2, 0]) square([6, 3]);"),
      6);
}

// Points on both sides of the axis: no solid, OpenSCAD's error line.
TEST(Scad2d, RotateExtrudeAcrossTheAxisIsEmptyWithOpenScadsError) {
  CsgNode n = fabatlas::scad::ParseCsg(
      "rotate_extrude(angle = 360, $fn = 0, $fa = 12, $fs = 2) { square(size = [4, 4], center = true); }",
      "across.csg");
  std::vector<std::string> warnings;
  const TriangleMesh m = fabatlas::scad::RotateExtrude(n.children[0], {}, &warnings);
  EXPECT_TRUE(m.empty());
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("must have the same X coordinate sign (range is -2.00 -> 2.00)"), std::string::npos)
      << warnings[0];
}

}  // namespace
