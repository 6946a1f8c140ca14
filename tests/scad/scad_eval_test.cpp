// OpenSCAD models evaluated by fabatlas: enum and string values reach
// OpenSCAD quoted (a string's length sets the geometry), and a string
// dropdown changes the geometry.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>

#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/scad/import_design.h"
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
