// fabatlas's own evaluation of OpenSCAD models (evaluate_model.h) against
// OpenSCAD 2021.01's `.csg` export of the same model at the same values: the
// same text, byte for byte, for the tray, sign.scad, candleStand.scad, the
// Fab Forms example models, the Customizer files of the import tests and
// every Debian example the evaluator takes; models it does not take are
// declined naming the line, and then OpenSCAD's export is used (the
// fallback path, exercised through the openscad node).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/mesh/enclosed_volume.h"
#include "fabatlas/mesh/read_mesh.h"
#include "fabatlas/scad/csg_tree.h"
#include "fabatlas/scad/evaluate_model.h"
#include "fabatlas/testing/paths.h"

namespace {

namespace fs = std::filesystem;
namespace scad = fabatlas::scad;
namespace design = fabatlas::design;
using Overrides = std::vector<std::pair<std::string, std::string>>;

std::string Read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// OpenSCAD's own export of `model` with `overrides`.
std::string OpenScadCsg(const fs::path& model, const Overrides& overrides, const fs::path& dir) {
  const fs::path out = dir / "peer.csg";
  fs::remove(out);
  scad::OpenScadRun run;
  EXPECT_TRUE(scad::RunOpenScad(model, out, overrides, &run)) << model << ": " << run.log_tail;
  return Read(out);
}

void ExpectSameAsOpenScad(const fs::path& model, const Overrides& overrides, const fs::path& dir) {
  const scad::ModelEvaluation own = scad::EvaluateModel(model, overrides);
  std::string at;
  for (const auto& [k, v] : overrides) at += " -D " + k + "=" + v;
  ASSERT_TRUE(own.evaluated) << model << at << ": " << own.declined;
  EXPECT_EQ(own.csg, OpenScadCsg(model, overrides, dir)) << model << at;
}

const fs::path kExamples = "/usr/share/openscad/examples";

TEST(ScadNative, TrayCandleStandSignAndTheExampleModelsAreOpenScadsExport) {
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-native");
  const fs::path source = fabatlas::testing::SourceDir();
  const fs::path tray = source / "configs/scad/tray.scad";
  ExpectSameAsOpenScad(tray, {}, dir);
  // holes = 0: OpenSCAD's [0 : -1] runs from -1 to 0 (its deprecated swap).
  ExpectSameAsOpenScad(tray, {{"holes", "0"}, {"shape", "\"square\""}, {"wall", "0.4"}, {"width", "120"}}, dir);
  ExpectSameAsOpenScad(tray, {{"holes", "8"}, {"wall", "5.8"}, {"width", "31"}}, dir);
  const fs::path candle = kExamples / "Parametric/candleStand.scad";
  ExpectSameAsOpenScad(candle, {}, dir);
  ExpectSameAsOpenScad(candle, {{"count", "3"}, {"length", "70"}}, dir);
  ExpectSameAsOpenScad(candle, {{"count", "14"}, {"centerCandle", "false"}}, dir);
  const fs::path sign = kExamples / "Parametric/sign.scad";
  ExpectSameAsOpenScad(sign, {}, dir);
  ExpectSameAsOpenScad(sign, {{"Message", "\"Thank You\""}, {"resolution", "30"}, {"radius", "123"}}, dir);
  for (const char* model : {"yinyang_handle.scad", "toy_car_wheel.scad", "holey_vase_holes.scad"})
    ExpectSameAsOpenScad(source / "configs/scad" / model, {}, dir);
}

// The language the evaluator implements, each form against OpenSCAD: scopes
// (assignments before instantiations, $-variables dynamic), modules with
// defaults and children, functions with recursion, list comprehensions,
// ranges, if/else, let, vector and matrix arithmetic, the built-in modules.
TEST(ScadNative, LanguageFormsAreOpenScadsExport) {
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-native-forms");
  const char* programs[] = {
      // scopes: use before assignment at the top, $fn in a child block, in a module, passed as an argument
      "cylinder(h, r);\nh = 3; r = 2;\ndifference() { $fn = 12; cylinder(h = 2, r = 3); sphere(1); }\n"
      "module m(a, b = 2) { $fa = 5; cube([a, b, 1]); children(); children(1); }\n"
      "m(1) { sphere(2); cylinder(r = 1, h = 2, $fn = 7); }\nm(b = 4, a = 2, $fs = 0.5) sphere(1);\n",
      // children and $children through two modules, children(i) out of range
      "module ring(n) for (a = [0 : n - 1]) rotate(a * 360 / n) translate([5, 0]) children();\n"
      "module both() { ring(5) children(0); echo($children); children(3); }\nboth() { cube(1); sphere(1); }\n",
      // functions, recursion, comprehensions, ranges, let, ?:, lookup, str, len, concat
      "function fact(n) = n <= 1 ? 1 : n * fact(n - 1);\nfunction pts(n, r) = [for (i = [0 : n - 1]) "
      "let(a = i * 360 / n) r * [cos(a), sin(a)]];\nv = [for (i = [1:3]) i * 2, each [7, 8], if (true) 9 else 10, "
      "for (i = [10 : -3 : 0]) if (i % 2 == 0) i];\nlinear_extrude(height = fact(3), twist = 30, slices = 4) "
      "polygon(pts(7, 4));\ntranslate([len(v), v[3], lookup(2.5, [[1, 10], [2, 20], [3, 40]])]) cube(concat([1], [2, "
      "3]));\n"
      "text(str(\"n\", 12, \"x\"), size = 4, halign = \"center\");\nfor (i = [0 : 0.25 : 1], j = [1, 2]) "
      "translate([i, j, 0]) cube(0.1);\n",
      // if/else chains, let statements, disabled statements, matrices, mirror, scale, multmatrix, colour
      "a = 3;\nif (a > 5) cube(1); else if (a > 2) sphere(a); else cylinder(1);\nif (false) cube(9);\n"
      "let (b = a * 2) translate([b, 0, 0]) cube(b);\n*cube(100);\nm = [[1, 2], [3, 4]] * [[0, 1], [1, 0]];\n"
      "translate(m[0] * 2) mirror([1, 1, 0]) scale([1, 2]) color([0.5, 0.2, 0.1], 0.5) cube(1);\n"
      "multmatrix([[1, 0.2, 0, 1], [0, 1, 0, 2], [0, 0, 1, 3]]) rotate(33, [1, 1, 0]) rotate([90, 45, 30]) cube(2);\n"
      "rotate_extrude(angle = 270, $fn = 24) translate([10, 0]) square([2, 3], center = true);\n"
      "hull() { sphere(d = 3); translate([5, 0, 0]) cylinder(d1 = 2, d2 = 1, h = 3, center = true); }\n"
      "intersection() { cube(5, center = true); sphere(3); }\nunion();\nrender() polyhedron(points = [[0, 0, 0], "
      "[1, 0, 0], [0, 1, 0], [0, 0, 1]], faces = [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]]);\n"
      "linear_extrude(5, scale = 0.5, center = true) circle(d = 4.5);\nx = 2 ^ 3 + -1 % 3;\ncube(x);\n",
      // number text: nodes as C's %g, matrices and vectors OpenSCAD's own way (ties away from zero, 1e+6, 2.5e-7)
      "translate([100.0625, 1e6, 2.5e-7]) cube([100.0625, 1e-5, 123456789]);\n"
      "polygon([[1e6, 1e-5], [123456789, -2.5e-7], [0.0001, 100000], [-0.00012345678, 1234567]]);\n"
      "// colours by name and hex, modifiers, offset, projection, convexity as a whole number\n"
      "color(\"LightBlue\") cube(1);\ncolor(\"#ff000080\") sphere(1);\ncolor(\"red\", 0.5) cylinder(1);\n"
      "%cube(2);\ntranslate([1, 0, 0]) #sphere(2);\n%if (true) cube(3);\n%for (i = [0 : 1]) cube(i);\n"
      "offset(r = 1) square(1);\noffset(delta = 1, chamfer = true) square(1);\nprojection(cut = true) cube(1);\n"
      "linear_extrude(height = 3, convexity = 3.7, slices = 2.5) circle(1);\n"
      "// names starting with digits, echo and assert in expressions and as statements, 2D cross, str\n"
      "function 3d(v) = [v.x, v.y, 0];\ny = echo(\"y\") assert(true) cross([1, 2], [3, 4]);\n"
      "translate(3d([y, 2])) cube(1);\nassert(true);\nassert(true) cube(1);\necho(\"e\") cube(2);\n"
      "text(str(\"6! = \", 720, \" \", 0.5));\n"
      "intersection_for(i = [0 : 2]) rotate([0, 0, i * 30]) cube(10, center = true);\n"
      "intersection_for(n = [1 : 6]) { rotate([0, 0, n * 60]) translate([5, 0, 0]) sphere(r = 12); }\n",
      // child(), deprecated but evaluated by OpenSCAD 2021.01: the first child, not a group; child(i), out of range
      "module m() { child(); translate([5, 0, 0]) child(1); child(7); }\nm() { cube(1); sphere(1); }\n",
      // binary operators: each precedence level against the next, left associativity
      "p = 1 + 2 * 3 - 8 / 4 % 3;\nq = p < 6 == false || p >= 5 && !(p != 5);\nr = 2 * 3 % 4 - 1 - 1;\n"
      "s = false && true || true;\nt = 1 < 2 == 2 > 1 != false;\n"
      "translate([p, r, 10 - 4 - 3]) cube([q ? 2 : 3, s ? 4 : 5, t ? 6 : 7]);\n",
  };
  int k = 0;
  for (const char* program : programs) {
    const fs::path model = dir / ("form" + std::to_string(k++) + ".scad");
    std::ofstream(model) << program;
    ExpectSameAsOpenScad(model, {}, dir);
  }
}

// Every example Debian's openscad ships: what the evaluator takes is
// OpenSCAD's export; the rest is declined naming a line of the example.
TEST(ScadNative, DebianExamplesTakenAreOpenScadsExportTheRestDeclined) {
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-native-examples");
  int taken = 0, declined = 0;
  std::vector<fs::path> models;
  for (const auto& group : fs::directory_iterator(kExamples))
    if (group.is_directory())
      for (const auto& f : fs::directory_iterator(group.path()))
        if (f.path().extension() == ".scad") models.push_back(f.path());
  std::sort(models.begin(), models.end());
  for (const fs::path& model : models) {
    const scad::ModelEvaluation own = scad::EvaluateModel(model, {});
    if (!own.evaluated) {
      ++declined;
      EXPECT_EQ(own.declined.rfind(model.string() + ":", 0), 0u) << own.declined;
      continue;
    }
    ++taken;
    EXPECT_EQ(own.csg, OpenScadCsg(model, {}, dir)) << model;
  }
  std::cout << taken << " of " << models.size() << " examples evaluated natively, " << declined << " declined\n";
  EXPECT_GE(taken, 34);
}

// OpenSCAD's own modifier regression models (openscad-testing-data's
// 3D/features: background `%`, highlight `#`, disable `*`, root `!`, and
// `%child()` inside a module, whose modifier OpenSCAD 2021.01 drops): what
// the evaluator takes is OpenSCAD's export byte for byte; the rest is
// declined naming a line of the model.
TEST(ScadNative, ModifierModelsAreOpenScadsExport) {
  const fs::path features = "/usr/share/openscad/testdata/scad/3D/features";
  if (!fs::exists(features)) GTEST_SKIP() << "openscad-testing-data not installed";
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-native-modifiers");
  int taken = 0;
  for (const char* name : {"background-modifier.scad", "background-modifier2.scad", "child-background.scad",
                           "disable-modifier.scad", "highlight-and-background-modifier.scad", "highlight-modifier.scad",
                           "highlight-modifier2.scad", "root-modifier.scad"}) {
    const fs::path model = features / name;
    const scad::ModelEvaluation own = scad::EvaluateModel(model, {});
    if (!own.evaluated) {
      EXPECT_EQ(own.declined.rfind(model.string() + ":", 0), 0u) << own.declined;
      continue;
    }
    ++taken;
    EXPECT_EQ(own.csg, OpenScadCsg(model, {}, dir)) << model;
  }
  EXPECT_GE(taken, 6);
}

// Models that include and use other files, nobody on the team wrote but
// the README's spur gear: models calling MCAD's modules (openscad-mcad),
// every MCAD library file read as a model, and OpenSCAD's own include/use
// regression models (openscad-testing-data: nested and relative paths,
// names with spaces, missing files, recursive includes, a variable
// assigned again by an included file). What the evaluator takes is
// OpenSCAD's export byte for byte.
TEST(ScadNative, IncludedAndUsedFilesAreOpenScadsExport) {
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-native-use");
  const fs::path gear = fabatlas::testing::SourceDir() / "configs/scad/spur_gear.scad";
  ExpectSameAsOpenScad(gear, {}, dir);
  ExpectSameAsOpenScad(gear, {{"teeth", "8"}, {"thickness", "12"}, {"bore", "24"}}, dir);
  ExpectSameAsOpenScad(gear, {{"teeth", "40"}, {"thickness", "2"}, {"bore", "2"}}, dir);
  const char* programs[] = {
      "use <MCAD/involute_gears.scad>\ntest_gears();\n",
      "use <MCAD/involute_gears.scad>\ntest_bevel_gear_pair();\ntranslate([0, 0, 40]) test_backlash();\n",
      "include <MCAD/stepper.scad>\nmotor(Nema17);\n",
      "use <MCAD/boxes.scad>\nroundedBox([20, 30, 10], 3, false);\ntranslate([30, 0]) roundedBox([20, 30, 10], 3, "
      "true);\n",
      "use <MCAD/servos.scad>\nalignds420([0, 0, 0], [0, 0, 0], screws = 1);\n",
      "include <MCAD/nuts_and_bolts.scad>\ndifference() { cube(20); boltHole(3, length = 30); nutHole(4); }\n",
      "use <MCAD/teardrop.scad>\nuse <MCAD/regular_shapes.scad>\nteardrop(5, 20, 90);\n"
      "translate([20, 0]) hexagon_tube(10, 8, 2);\ntranslate([40, 0]) torus(10, 6);\n",
      // assign(), deprecated but evaluated by OpenSCAD 2021.01 (involute_gears.scad uses it)
      "x = 5;\nassign(a = 2, b = x, x = 1) { cube(a); sphere(b); }\nassign(a = 1) cube(a);\nassign(a = 1);\n",
      // bare { } blocks: their statements are the enclosing scope's (assignments, definitions, children)
      "{ a = 2; cube(a); module q() sphere(3); }\nb = a + 1;\ncube(b);\nq();\n"
      "module m() { echo($children); children(1); }\nm() { { cube(5); sphere(6); } cylinder(7); }\n"
      "module n() { x = 1; { x = 4; y = 2; } cube([x, y, 1]); }\nn();\nif (true) { { z = 3; } cube(z); }\n",
      "use <MCAD/involute_gears.scad>\ntest_meshing_double_helix();\n",
  };
  int k = 0;
  for (const char* program : programs) {
    const fs::path model = dir / ("uses" + std::to_string(k++) + ".scad");
    std::ofstream(model) << program;
    ExpectSameAsOpenScad(model, {}, dir);
  }
  // A used file's modules see its own top-level variables (not the model's),
  // and its top-level $fn; its top-level assignments read the caller's
  // $-variables; its instantiations are not run. An included file's
  // instantiations are; a variable assigned again keeps the last value at
  // the first place.
  fs::create_directories(dir / "lib/sub");
  std::ofstream(dir / "lib/sub/inner.scad") << "module inner(r) sphere(r);\nk = 2;\ncube(7);\n";
  std::ofstream(dir / "lib/outer.scad") << "use <sub/inner.scad>\nv = 3;\n$fn = 7;\nw = $fa;\n"
                                        << "module m() { cube(v); inner(1); cube(w); }\nfunction f() = v * 2;\n"
                                        << "cube(100);\n";
  std::ofstream(dir / "lib/parts.scad") << "size = 4;\ncube(size);\nmodule part() cylinder(h = size, r = 1);\n";
  std::ofstream(dir / "scopes.scad") << "use <lib/outer.scad>\nv = 10;\n$fa = 5;\nm();\ncube(f());\n"
                                     << "translate([1, 0, 0]) m($fa = 9);\ninclude <lib/parts.scad>\npart();\n"
                                     << "size = 6;\nmodule pm(a) { a = a + 2; cube(a); }\npm(1);\n";
  ExpectSameAsOpenScad(dir / "scopes.scad", {}, dir);
  ExpectSameAsOpenScad(dir / "scopes.scad", {{"size", "2"}, {"v", "1"}}, dir);
  // Where a used file is found: beside the model first, then in OPENSCADPATH.
  fs::create_directories(dir / "path_lib");
  fs::create_directories(dir / "beside");
  fs::create_directories(dir / "elsewhere");
  std::ofstream(dir / "path_lib/p.scad") << "module p() cube(3);\n";
  std::ofstream(dir / "beside/p.scad") << "module p() sphere(2);\n";
  for (const char* d : {"beside", "elsewhere"}) std::ofstream(dir / d / "model.scad") << "use <p.scad>\np();\n";
  const char* was = std::getenv("OPENSCADPATH");
  const std::string before = was ? was : "";
  setenv("OPENSCADPATH", (dir / "path_lib").c_str(), 1);
  ExpectSameAsOpenScad(dir / "beside/model.scad", {}, dir);
  ExpectSameAsOpenScad(dir / "elsewhere/model.scad", {}, dir);
  EXPECT_NE(scad::EvaluateModel(dir / "beside/model.scad", {}).csg.find("sphere("), std::string::npos);
  EXPECT_NE(scad::EvaluateModel(dir / "elsewhere/model.scad", {}).csg.find("cube("), std::string::npos);
  if (was)
    setenv("OPENSCADPATH", before.c_str(), 1);
  else
    unsetenv("OPENSCADPATH");
  // A model including itself through a link to its own directory: OpenSCAD
  // includes it once (the link resolved, the second time is a cycle).
  fs::create_directories(dir / "loop");
  fs::create_directory_symlink(".", dir / "loop/again");
  std::ofstream(dir / "loop/self.scad") << "cube(1);\ninclude <again/self.scad>\n";
  ExpectSameAsOpenScad(dir / "loop/self.scad", {}, dir);
  const fs::path misc = "/usr/share/openscad/testdata/scad/misc";
  for (const char* model :
       {"include-tests.scad", "include-recursive-test.scad", "include-overwrite-main.scad", "sub2/useuse.scad"})
    ExpectSameAsOpenScad(misc / model, {}, dir);
  // include-tests.scad names files that do not exist: skipped, as OpenSCAD
  // skips them, each with a line naming the place.
  const scad::ModelEvaluation tests = scad::EvaluateModel(misc / "include-tests.scad", {});
  const std::string missing =
      (misc / "include-tests.scad").string() + ":8: include <non/existent/path/non-file>: not found (beside ";
  EXPECT_EQ(std::count_if(tests.warnings.begin(), tests.warnings.end(),
                          [&](const std::string& w) { return w.rfind(missing, 0) == 0; }),
            1);
  EXPECT_EQ(tests.warnings.size(), 4u);  // and sub1/not_exist.scad, test/ (a directory), /
  // Every MCAD file read as a model (most define modules only; some draw a
  // demonstration): all but two are OpenSCAD's export; hardware.scad
  // compares undef (where OpenSCAD warns) and regular_shapes.scad calls a
  // module it does not define, declined naming their own line.
  int taken = 0;
  for (const auto& f : fs::directory_iterator("/usr/share/openscad/libraries/MCAD")) {
    if (f.path().extension() != ".scad") continue;
    const scad::ModelEvaluation own = scad::EvaluateModel(f.path(), {});
    if (!own.evaluated) {
      EXPECT_EQ(own.declined.rfind(f.path().string() + ":", 0), 0u) << own.declined;
      continue;
    }
    ++taken;
    EXPECT_EQ(own.csg, OpenScadCsg(f.path(), {}, dir)) << f.path();
  }
  EXPECT_GE(taken, 31);
}

// The README's spur gear (`use <MCAD/involute_gears.scad>`) through the
// openscad node: its sample needs no OpenSCAD (it evaluates with OpenSCAD
// off the PATH), and its volume is OpenSCAD's own STL's.
TEST(ScadNative, TheSpurGearSampleRunsNoOpenScad) {
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-native-gear");
  fs::copy_file(fabatlas::testing::SourceDir() / "configs/scad/spur_gear.scad", dir / "spur_gear.scad");
  std::ofstream(dir / "d.yaml") << "name: d\nvoxel_size: 0.5\n"
                                << "parameters: {teeth: {type: integer, min: 8, max: 40, default: 17}}\n"
                                << "tree: {op: openscad, file: spur_gear.scad, set: {teeth: teeth}}\n"
                                << "properties: [volume]\n";
  scad::OpenScadRun run;
  ASSERT_TRUE(scad::RunOpenScad(dir / "spur_gear.scad", dir / "peer.stl", {{"teeth", "11"}}, &run)) << run.log_tail;
  const double theirs = std::abs(fabatlas::mesh::EnclosedVolume(fabatlas::mesh::ReadMesh(dir / "peer.stl")));
  const std::string path = std::getenv("PATH") ? std::getenv("PATH") : "";
  setenv("PATH", (dir / "no-programs-here").c_str(), 1);
  design::SampleResult r;
  try {
    const design::Design d = design::LoadDesign(dir / "d.yaml");
    r = design::EvaluateSample(d, design::ParsePoint(d, "teeth=11", "--at"), {});
  } catch (const std::exception& e) {
    ADD_FAILURE() << e.what();
  }
  setenv("PATH", path.c_str(), 1);
  ASSERT_TRUE(r.valid) << r.failure << ": " << r.failure_reason;
  EXPECT_NEAR(r.solid.Volume(), theirs, 1e-4 * theirs);
  for (const auto& record : r.subtrees) EXPECT_EQ(record.op.rfind("csg-openscad", 0), std::string::npos) << record.op;
}

// A place in an included or used file is named by that file, and a file
// that cannot be parsed declines naming it (OpenSCAD then reports it).
TEST(ScadNative, ADeclinedPlaceInALibraryNamesTheLibrary) {
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-native-use-declined");
  std::ofstream(dir / "lib.scad") << "module m() {\n  minkowski() { cube(1); sphere(1); }\n}\n";
  std::ofstream(dir / "broken.scad") << "module b() {\n  cube(1);\n";
  std::ofstream(dir / "uses.scad") << "use <lib.scad>\ncube(1);\nm();\n";
  std::ofstream(dir / "includes.scad") << "cube(1);\ninclude <broken.scad>\n";
  std::ofstream(dir / "unclosed.scad") << "cube(1);\nuse <lib.scad\ncube(2);\n";
  EXPECT_EQ(scad::EvaluateModel(dir / "uses.scad", {}).declined,
            (dir / "lib.scad").string() + ":2: module minkowski()");
  EXPECT_EQ(scad::EvaluateModel(dir / "includes.scad", {}).declined,
            (dir / "broken.scad").string() + ":3: unclosed '{'");
  EXPECT_EQ(scad::EvaluateModel(dir / "unclosed.scad", {}).declined,
            (dir / "unclosed.scad").string() + ":2: use <lib.scad without '>'");
}

TEST(ScadNative, WhatItDoesNotImplementIsDeclinedNamingTheLine) {
  const std::pair<const char*, const char*> cases[] = {
      {"cube(1);\nminkowski() { cube(1); sphere(1); }\n", "m.scad:2: module minkowski()"},
      {"\n!cube(1);\n", "m.scad:2: modifier '!'"},
      {"a = undef;\ncube(a + 1);\n", "m.scad:2: operator + on these operands"},
      {"text(\"\\u263A\");\n", "m.scad:1: a \\x or \\u escape"},
      {"cube(b);\n", "m.scad:1: unknown variable 'b'"},
      {"intersection_for(i = [1, 2]) { cube(i); sphere(i); }\n",
       "m.scad:1: intersection_for with an iteration making other than one node"},
  };
  // Recursion: 100 levels of a function and of a module are evaluated, a
  // million are declined within the evaluator's stack budget (no crash).
  const std::string deep =
      "function f(n) = n <= 0 ? 0 : 1 + f(n - 1);\nmodule m(n) { if (n > 0) m(n - 1); else cube(f(N)); }\nm(N);\n";
  auto depth = [&](const std::string& n) {
    std::string p = deep;
    for (std::size_t at; (at = p.find('N')) != std::string::npos;) p.replace(at, 1, n);
    return scad::EvaluateModelText(p, "m.scad", {});
  };
  EXPECT_TRUE(depth("100").evaluated) << depth("100").declined;
  EXPECT_NE(depth("100").csg.find("cube(size = [100, 100, 100]"), std::string::npos);
  EXPECT_EQ(depth("1000000").declined, "m.scad:2: recursion deeper than the evaluator's stack budget");
  // Exponential work (2^40 calls) declines after a bounded number of steps.
  EXPECT_EQ(scad::EvaluateModelText("function f(n) = n == 0 ? 1 : f(n - 1) + f(n - 1);\ncube(f(40));\n", "m.scad", {})
                .declined,
            "m.scad:1: more than 20 million evaluation steps");
  // Doubling a vector 30 times declines before it takes the memory.
  EXPECT_EQ(scad::EvaluateModelText("function g(v, n) = n == 0 ? v : g(concat(v, v), n - 1);\ncube(len(g([1], 30)));\n",
                                    "m.scad", {})
                .declined,
            "m.scad:1: a vector of more than 1,000,000 values");
  // Growing a 300,000-value vector by one at each of 100 levels of recursion
  // (each level keeps its copy: 30 million values, gigabytes) declines at
  // two million values built.
  EXPECT_EQ(scad::EvaluateModelText("function g(v, n) = n == 0 ? len(v) : g(concat(v, [n]), n - 1);\n"
                                    "cube(g([for (i = [1 : 300000]) i], 100) > 0 ? 1 : 2);\n",
                                    "m.scad", {})
                .declined,
            "m.scad: more than 2 million vector values built");
  for (const auto& [program, reason] : cases) {
    const scad::ModelEvaluation own = scad::EvaluateModelText(program, "m.scad", {});
    EXPECT_FALSE(own.evaluated) << program;
    EXPECT_EQ(own.declined, reason) << program;
  }
  // An unknown colour name is not declined but bad input (OpenSCAD would
  // draw it grey), with its line (docs/openscad.md, "Parts and colours").
  const scad::ModelEvaluation colour =
      scad::EvaluateModelText("cube(1);\ncolor(\"notacolour\") cube(1);\n", "m.scad", {});
  EXPECT_FALSE(colour.evaluated);
  EXPECT_EQ(
      colour.bad_input,
      "m.scad:2: color(\"notacolour\"): unknown colour name (an SVG/CSS colour name, \"#rrggbb\" or [r, g, b, a])");
  EXPECT_EQ(scad::UnknownColourName(
                "cube(1);\n// color(\"x\")\ncolor(c = \"Reddish\", alpha = 0.5) cube(1);\ncolor(\"Red\") cube(1);\n",
                "m.scad"),
            "m.scad:3: color(\"Reddish\"): unknown colour name (an SVG/CSS colour name, \"#rrggbb\" or [r, g, b, a])");
  EXPECT_EQ(scad::UnknownColourName("color(\"#a0b0c0\") color(\"DarkOrchid\") cube(1);\n", "m.scad"), "");
}

// The openscad node: a model the evaluator takes needs no OpenSCAD (it
// evaluates with OpenSCAD off the PATH), one it declines is exported by
// OpenSCAD (and without OpenSCAD fails saying so).
TEST(ScadNative, TheOpenScadNodeFallsBackToOpenScadsExport) {
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-native-node");
  std::ofstream(dir / "plain.scad") << "s = 10;\ncube(s);\n";
  std::ofstream(dir / "rounded.scad") << "s = 10;\nminkowski() { cube(s - 2); sphere(1, $fn = 8); }\n";
  auto load = [&](const char* model) {
    std::ofstream(dir / "d.yaml")
        << "name: d\nvoxel_size: 0.25\nparameters: {s: {type: real, min: 4, max: 12, default: 10}}\n"
        << "tree: {op: openscad, file: " << model << ", set: {s: s}}\nproperties: [volume]\n";
    return design::LoadDesign(dir / "d.yaml");
  };
  auto volume = [&](const design::Design& d, bool* failed = nullptr) {
    design::SampleResult r;
    try {
      r = design::EvaluateSample(d, design::ParsePoint(d, "s=8", "--at"), {});
    } catch (const std::exception& e) {
      if (failed) *failed = true;
      return 0.0;
    }
    if (failed) *failed = !r.valid;
    return r.valid ? r.solid.Volume() : 0.0;
  };
  const design::Design plain = load("plain.scad"), rounded = load("rounded.scad");
  EXPECT_NEAR(volume(plain), 512, 5);
  // minkowski of a 6 mm cube and a sphere of radius 1 (8 fragments): OpenSCAD renders it.
  const double with_openscad = volume(rounded);
  EXPECT_GT(with_openscad, 6 * 6 * 6 + 6 * 6 * 6);  // the cube and its faces pushed out by 1 mm
  EXPECT_LT(with_openscad, 8 * 8 * 8);
  const std::string path = std::getenv("PATH") ? std::getenv("PATH") : "";
  setenv("PATH", (dir / "no-programs-here").c_str(), 1);
  const design::Design plain_again = load("plain.scad");
  EXPECT_NEAR(volume(plain_again), 512, 5);
  const design::Design rounded_again = load("rounded.scad");
  bool failed = false;
  volume(rounded_again, &failed);
  setenv("PATH", path.c_str(), 1);
  EXPECT_TRUE(failed) << "the declined model evaluated without OpenSCAD";
}

}  // namespace
