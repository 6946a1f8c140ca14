// Assemblies as a design family for precompute: configs/assemblies/clip_lights_family.yaml
// evaluated through the design model (op `assembly`, checks
// assembly_feasible / assembly_stable / target_reached).
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "fabatlas/design/design.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/error.h"
#include "fabatlas/testing/paths.h"

using namespace fabatlas;

namespace {

design::Design ClipLights() {
  return design::LoadDesign(fabatlas::testing::SourceDir() / "configs/assemblies/clip_lights_family.yaml");
}

const design::CheckOutcome& Check(const design::SampleResult& r, const std::string& name) {
  for (const auto& c : r.checks)
    if (c.name == name) return c;
  throw std::runtime_error("no check " + name);
}

}  // namespace

TEST(AssemblyDesignFamily, ExtensionStepsLowerTheLightByTheirLength) {
  const design::Design d = ClipLights();
  const design::SampleResult a =
      design::EvaluateSample(d, design::ParsePoint(d, "pairs=1,extension_step=0,ring=S", "--at"));
  const design::SampleResult b =
      design::EvaluateSample(d, design::ParsePoint(d, "pairs=1,extension_step=19,ring=S", "--at"));
  for (const auto* r : {&a, &b}) {
    ASSERT_TRUE(Check(*r, "geometry").passed) << Check(*r, "geometry").reason;
    ASSERT_TRUE(Check(*r, "assembly_feasible").passed) << Check(*r, "assembly_feasible").reason;
    ASSERT_EQ(Check(*r, "target_reached").measures.count("target_deviation"), 1u);
  }
  // The chain hangs straight: 19 steps of 2.285 mm (45.7/20) lower the
  // light, its lowest point, by 43.4 mm, towards the target below it.
  const double da = Check(a, "target_reached").measures.at("target_deviation");
  const double db = Check(b, "target_reached").measures.at("target_deviation");
  EXPECT_GT(da - db, 0.5 * 19 * 2.285);
  EXPECT_NEAR(a.solid.BoundingBox().min[2] - b.solid.BoundingBox().min[2], 19 * 2.285, 3.0 + 2 * d.voxel_size);
  // The parts hang from the ceiling hook at z = 1000 mm.
  EXPECT_GT(a.solid.BoundingBox().max[2], 950);
  EXPECT_LT(a.solid.BoundingBox().max[2], 1030);
}

TEST(AssemblyDesignFamily, AssemblyChecksNeedAnAssemblyNode) {
  const auto file = fabatlas::testing::FreshTempDir("assembly_family") / "no_assembly.yaml";
  {
    std::ofstream out(file);
    out << "parameters: {r: {type: real, min: 1, max: 2}}\ntree: {op: sphere, radius: r}\nchecks: [assembly_stable]\n";
  }
  try {
    design::LoadDesign(file);
    FAIL() << "loaded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no_assembly.yaml:3:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("needs an 'assembly' node"), std::string::npos) << e.what();
  }
}
