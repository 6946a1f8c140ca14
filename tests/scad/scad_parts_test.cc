// Parts and colours (docs/openscad.md, "Parts and colours"): an OpenSCAD
// model's top-level bodies and color() regions kept through evaluation,
// against the colours OpenSCAD 2021.01 itself resolves (its .csg export) and
// the CSS/SVG colour keywords' published values; volumes analytic.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "fabatlas/design/design.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/error.h"
#include "fabatlas/mesh/enclosed_volume.h"
#include "fabatlas/mesh/mesh_report.h"
#include "fabatlas/scad/csg_tree.h"
#include "fabatlas/scad/part_trees.h"
#include "fabatlas/testing/paths.h"

namespace {

namespace fs = std::filesystem;
namespace design = fabatlas::design;
namespace mesh = fabatlas::mesh;
namespace scad = fabatlas::scad;

const fs::path kFeatures = "/usr/share/openscad/testdata/scad/3D/features";

// The model at its own values on the mesh road, with its parts.
design::SampleResult Evaluate(const fs::path& model, const fs::path& dir, std::vector<design::Part>* parts) {
  design::Design d = design::ParseDesign(
      "name: parts\nvoxel_size: 0.5\nparameters: {unused: {type: integer, min: 0, max: 1, default: 0}}\n"
      "tree: {op: openscad, file: '" +
          model.string() + "'}\n",
      dir / "parts.yaml");
  design::EvaluateOptions options;
  options.run_checks = false;
  options.parts = parts;
  return design::EvaluateSample(d, design::DefaultPoint(d), options);
}

fs::path Write(const fs::path& dir, const std::string& name, const std::string& text) {
  std::ofstream(dir / name) << text;
  return dir / name;
}

// OpenSCAD's own answer: per top-level statement of its .csg export, the
// innermost color() it resolved (a name or #hex becomes numbers; [-1, ...]
// is "no colour"), read from the text line by line.
std::vector<std::string> OpenScadColours(const fs::path& model, const fs::path& dir) {
  const fs::path csg = dir / (model.stem().string() + ".peer.csg");
  const std::string command = "cd '" + model.parent_path().string() + "' && openscad --quiet -o '" + csg.string() +
                              "' '" + model.string() + "' 2>/dev/null";
  EXPECT_EQ(std::system(command.c_str()), 0) << command;
  std::ifstream in(csg);
  std::vector<std::string> out;
  std::string line;
  const std::regex colour(R"(color\(\[([^\]]*)\]\))");
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    if (line[0] != '\t' && line[0] != '}') out.push_back("none");
    std::smatch m;
    if (std::regex_search(line, m, colour) && m[1].str().rfind("-1", 0) != 0) out.back() = m[1].str();
  }
  return out;
}

// OpenSCAD's colour regression model: nine cubes of 10 mm, by vector, name,
// vector and alpha, name and alpha, none, alpha alone, and one colour inside
// another (the inner wins).
TEST(Parts, OpenScadsColourTestsKeepEveryBodyInOpenScadsColour) {
  const fs::path model = kFeatures / "color-tests.scad";
  if (!fs::exists(model)) GTEST_SKIP() << "openscad-testing-data is not installed";
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-parts-colours");
  std::vector<design::Part> parts;
  const design::SampleResult r = Evaluate(model, dir, &parts);
  ASSERT_TRUE(r.valid) << r.failure_reason;
  // The CSS/SVG keywords' values (CSS Color Module Level 3, 4.3): purple and
  // green are (128, 0, 128) and (0, 128, 0) of 255.
  const double k128 = 128.0 / 255;
  struct Expected {
    const char* name;
    bool coloured;
    std::array<double, 4> rgba;
  };
  const std::vector<Expected> expected = {{"body3", false, {}},
                                          {"body4", true, {1, 0, 0, 1}},
                                          {"body5", true, {k128, 0, k128, 1}},
                                          {"body6", true, {0, 0, 1, 0.5}},
                                          {"body7", true, {0, 0, 1, 0.5}},
                                          {"body8", true, {0, k128, 0, 0.2}},
                                          {"body9", false, {}},
                                          {"body10", false, {}},
                                          {"body11", true, {0, 0, 1, 1}}};
  ASSERT_EQ(parts.size(), expected.size());
  double sum = 0;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    EXPECT_EQ(parts[i].name, expected[i].name);
    EXPECT_EQ(parts[i].coloured, expected[i].coloured) << parts[i].name;
    for (int k = 0; k < 4 && expected[i].coloured; ++k)
      EXPECT_NEAR(parts[i].rgba[k], expected[i].rgba[k], 1e-6) << parts[i].name;
    const double volume = mesh::EnclosedVolume(parts[i].mesh);
    EXPECT_NEAR(volume, 1000, 1e-9) << parts[i].name;
    sum += volume;
  }
  EXPECT_NEAR(sum, r.solid.Volume(), 1e-6);  // the sample's solid stays the union
  // And the colours are the ones OpenSCAD itself wrote, statement by statement.
  const std::vector<std::string> peer = OpenScadColours(model, dir);
  ASSERT_EQ(peer.size(), 11u);
  for (const auto& p : parts) {
    const int body = std::stoi(p.name.substr(4));
    std::vector<double> numbers;
    if (peer[body - 1] != "none") {
      std::istringstream s(peer[body - 1]);
      for (std::string x; std::getline(s, x, ',');) numbers.push_back(std::stod(x));
    }
    ASSERT_EQ(p.coloured, !numbers.empty()) << p.name << " against OpenSCAD's " << peer[body - 1];
    for (std::size_t k = 0; k < numbers.size(); ++k) EXPECT_NEAR(p.rgba[k], numbers[k], 1e-6) << p.name;
  }
}

// A union of differently coloured cubes keeps both colours (as OpenSCAD's
// preview shows them); the first keeps what they share, so the parts are
// disjoint and add up to the union. A difference keeps its first child's
// colours, each cut.
TEST(Parts, UnionKeepsBothColoursAndDifferenceItsFirstChilds) {
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-parts-union");
  const fs::path model =
      Write(dir, "union.scad",
            "union() { color(\"red\") cube(10); color(\"blue\") translate([5, 0, 0]) cube(10); }\n"
            "translate([0, 30, 0]) difference() {\n"
            "  union() { color(\"red\") cube(10); color(\"#00ff00\") translate([10, 0, 0]) cube(10); }\n"
            "  translate([5, -1, -1]) cube([10, 12, 12]);\n"
            "}\n");
  std::vector<design::Part> parts;
  const design::SampleResult r = Evaluate(model, dir, &parts);
  ASSERT_TRUE(r.valid) << r.failure_reason;
  ASSERT_EQ(parts.size(), 4u);
  EXPECT_EQ(parts[0].name, "body1-ff0000");
  EXPECT_EQ(parts[1].name, "body1-0000ff");
  EXPECT_EQ(parts[2].name, "body2-ff0000");
  EXPECT_EQ(parts[3].name, "body2-00ff00");
  const double volumes[] = {1000, 500, 500, 500};
  for (std::size_t i = 0; i < parts.size(); ++i) {
    EXPECT_NEAR(mesh::EnclosedVolume(parts[i].mesh), volumes[i], 1e-6) << parts[i].name;
    const mesh::MeshReport report = mesh::InspectMesh(parts[i].mesh);
    EXPECT_TRUE(report.closed) << parts[i].name << ": " << report.closed_reason;
  }
  EXPECT_NEAR(r.solid.Volume(), 2500, 1e-6);
}

// A model without colours and with one statement is one part, the solid.
TEST(Parts, OneUncolouredBodyIsTheSolid) {
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-parts-one");
  const fs::path model = Write(dir, "one.scad", "difference() { cube(10); translate([2, 2, 2]) cube(6); }\n");
  std::vector<design::Part> parts;
  const design::SampleResult r = Evaluate(model, dir, &parts);
  ASSERT_TRUE(r.valid) << r.failure_reason;
  ASSERT_EQ(parts.size(), 1u);
  EXPECT_EQ(parts[0].name, "body1");
  EXPECT_FALSE(parts[0].coloured);
  EXPECT_NEAR(mesh::EnclosedVolume(parts[0].mesh), 1000 - 216, 1e-9);
}

// color() with a name that is no colour: one line naming the model, the
// line and the name, whether fabatlas evaluates the model or OpenSCAD does
// (minkowski makes fabatlas ask OpenSCAD for the tree).
TEST(Parts, AnUnknownColourNameIsOneLineWithTheModelsLine) {
  const fs::path dir = fabatlas::testing::FreshTempDir("scad-parts-unknown");
  const fs::path ours = Write(dir, "ours.scad", "cube(1);\ncolor(\"reddish\") sphere(1);\n");
  const fs::path theirs =
      Write(dir, "theirs.scad", "minkowski() { cube(1); sphere(0.1); }\n\ncolor(\"reddish\") sphere(1);\n");
  for (const auto& [model, line] : {std::pair{ours, 2}, std::pair{theirs, 3}}) {
    try {
      Evaluate(model, dir, nullptr);
      ADD_FAILURE() << model << ": no error";
    } catch (const fabatlas::InputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what,
                model.string() + ":" + std::to_string(line) +
                    ": color(\"reddish\"): unknown colour name (an SVG/CSS colour name, \"#rrggbb\" or [r, g, b, a])");
      EXPECT_EQ(what.find('\n'), std::string::npos);
    }
  }
}

// The part programs of a tree: bodies are top-level statements; colour
// regions follow the innermost colour through transforms.
TEST(Parts, PartTreesFollowTheInnermostColourThroughTransforms) {
  const scad::CsgNode root = scad::ParseCsg(
      "multmatrix([[1,0,0,5],[0,1,0,0],[0,0,1,0],[0,0,0,1]]) { color([1,0,0,1]) { cube(size=[1,1,1]); "
      "color([0,0,1,1]) { sphere(r=1); } } }\n"
      "hull() { color([0,1,0,1]) { cube(size=[1,1,1]); } sphere(r=2); }\n",
      "t.csg");
  const std::vector<scad::PartTree> trees = scad::PartTrees(root);
  ASSERT_EQ(trees.size(), 3u);
  EXPECT_EQ(trees[0].body, 1);
  EXPECT_EQ(scad::HexColour(trees[0].rgba), "#ff0000");
  EXPECT_EQ(trees[0].csg, "multmatrix([[1,0,0,5],[0,1,0,0],[0,0,1,0],[0,0,0,1]]){cube(size=[1,1,1]);}");
  EXPECT_EQ(scad::HexColour(trees[1].rgba), "#0000ff");
  EXPECT_EQ(trees[2].body, 2);
  EXPECT_EQ(scad::HexColour(trees[2].rgba), "#00ff00");  // a hull takes the colour inside it
}

}  // namespace
