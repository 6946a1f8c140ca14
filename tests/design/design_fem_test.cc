// The fem check of design files (Fab Forms Sec. 8, docs/design-format.md):
// the sandal example, a cantilever against Euler-Bernoulli beam theory, and
// one-line errors for bad FEM arguments.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include "design_files.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/error.h"

using namespace fabatlas;
using fabatlas::testing::TempDesign;

namespace {

design::SampleResult Evaluate(const design::Design& d, const std::string& at = "") {
  return design::EvaluateSample(d, design::ParsePoint(d, at, "--at"));
}

const design::CheckOutcome& FemOutcome(const design::SampleResult& r) {
  for (const auto& c : r.checks)
    if (c.name == "fem") return c;
  ADD_FAILURE() << "no fem check ran (failure: " << r.failure << ": " << r.failure_reason << ")";
  static design::CheckOutcome none;
  return none;
}

// The check's reason ends with "max displacement <u> mm (limit ...)".
double MaxDisplacement(const design::CheckOutcome& c) {
  std::size_t at = c.reason.rfind("max displacement ");
  if (at == std::string::npos) return NAN;
  return std::stod(c.reason.substr(at + 17));
}

design::Design Sandal() { return design::LoadDesign(fabatlas::testing::SourceDir() / "configs/designs/sandal.yaml"); }

// A box beam [0,L] x [0,b] x [0,h] clamped at x = 0, tip load F down at x = L.
std::string Cantilever(double L, double b, double h, double fem_voxel, double E, double F, const std::string& fixed) {
  char text[2048];
  std::snprintf(text, sizeof text, R"(name: cantilever
voxel_size: 0.5
parameters:
  L: {type: real, min: 10, max: 400, default: %g}
tree:
  op: translate
  by: [L / 2, %g, %g]
  children:
    - {op: box, size: [L, %g, %g]}
checks:
  - type: fem
    voxel: %g
    youngs_modulus: %g
    poisson: 0.3
    fixed: %s
    loaded: [[L - 0.01, -1, -1], [L + 1, %g, %g]]
    force: [0, 0, -%g]
    max_displacement: 100
)",
                L, b / 2, h / 2, b, h, fem_voxel, E, fixed.c_str(), b + 1, h + 1, F);
  return text;
}

}  // namespace

TEST(DesignFem, SandalDefaultPasses) {
  design::Design d = Sandal();
  auto start = std::chrono::steady_clock::now();
  design::SampleResult r = Evaluate(d);
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const design::CheckOutcome& fem = FemOutcome(r);
  std::printf("sandal default: %s (%.2f s)\n", fem.reason.c_str(), seconds);
  EXPECT_TRUE(r.valid) << r.failure << ": " << r.failure_reason;
  EXPECT_TRUE(fem.passed);
  EXPECT_LT(MaxDisplacement(fem), 2.0);
  // The measured values are properties of the valid sample.
  EXPECT_DOUBLE_EQ(r.properties.at("fem_max_displacement"), fem.measures.at("fem_max_displacement"));
  EXPECT_NEAR(r.properties.at("fem_max_displacement"), MaxDisplacement(fem), 1e-3);
  EXPECT_GT(r.properties.at("fem_max_strain"), 0.0);
}

TEST(DesignFem, ThinTallHeelDeformsTooMuch) {
  design::Design d = Sandal();
  design::SampleResult r = Evaluate(d, "heel_height=80,heel_thickness=10");
  const design::CheckOutcome& fem = FemOutcome(r);
  std::printf("sandal thin tall heel: %s\n", fem.reason.c_str());
  EXPECT_FALSE(r.valid);
  EXPECT_EQ(r.failure, design::kTooMuchDeformation);
  EXPECT_FALSE(fem.passed);
  EXPECT_NE(r.failure_reason.find("max displacement"), std::string::npos) << r.failure_reason;
}

// Euler-Bernoulli: tip deflection of a clamped beam under an end load,
// delta = F L^3 / (3 E I), I = b h^3 / 12. The default incompatible-mode
// element does not lock in bending (docs/fem.md), so already 5 elements
// through the depth are within 1%; the 3D clamp and shear deformation
// (Timoshenko, +0.8% at L/h = 10) shift the answer by less. The load is small
// (delta/L = 1e-3), so the Neo-Hookean solution is in its linear range. The
// reported max |u| includes the tip's axial displacement from the end
// rotation (+0.3%).
TEST(DesignFem, CantileverMatchesEulerBernoulli) {
  const double L = 100, b = 10, h = 10, E = 1000, F = 0.25;
  const double I = b * h * h * h / 12;
  const double expected = F * L * L * L / (3 * E * I);  // 0.1 mm
  for (auto [voxel, tolerance] : {std::pair{2.0, 0.01}, std::pair{1.25, 0.01}}) {
    design::Design d =
        design::LoadDesign(TempDesign(Cantilever(L, b, h, voxel, E, F, "[[-1, -1, -1], [0.01, 11, 11]]")));
    auto start = std::chrono::steady_clock::now();
    design::SampleResult r = Evaluate(d);
    double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const design::CheckOutcome& fem = FemOutcome(r);
    double u = MaxDisplacement(fem);
    std::printf("cantilever voxel %g: %s; Euler-Bernoulli %.5f mm, ratio %.4f (%.2f s)\n", voxel, fem.reason.c_str(),
                expected, u / expected, seconds);
    EXPECT_TRUE(fem.passed);
    // SampleOccupancy aligns cells to multiples of the voxel: the beam is
    // exactly (L/v) x (b/v) x (h/v) hexahedra.
    const long elements = std::lround(L / voxel) * std::lround(b / voxel) * std::lround(h / voxel);
    EXPECT_NE(fem.reason.find(", " + std::to_string(elements) + " elements"), std::string::npos) << fem.reason;
    EXPECT_NEAR(u / expected, 1.0, tolerance) << "voxel " << voxel;
  }
}

// Bad FEM arguments are problems of the design: one-line InputError naming
// the check, never a crash or a silently passing sample.
void ExpectOneLineError(const std::string& text, const std::string& needle) {
  design::Design d = design::LoadDesign(TempDesign(text));
  try {
    Evaluate(d);
    ADD_FAILURE() << "no InputError (expected one mentioning '" << needle << "')";
  } catch (const InputError& e) {
    std::string what = e.what();
    std::printf("error: %s\n", what.c_str());
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_NE(what.find("check 'fem'"), std::string::npos) << what;
    EXPECT_NE(what.find(needle), std::string::npos) << what;
  }
}

// A region that selects nothing at a sample makes that sample invalid with
// its reason (the job goes on); it depends on the sample's geometry.
TEST(DesignFem, EmptyFixedRegionMakesTheSampleInvalid) {
  design::Design d =
      design::LoadDesign(TempDesign(Cantilever(100, 10, 10, 2, 1000, 0.25, "[[-10, -10, -10], [-5, -5, -5]]")));
  design::SampleResult r = Evaluate(d);
  EXPECT_FALSE(r.valid);
  EXPECT_EQ(r.failure, design::kLoadCaseMissesSolid);
  EXPECT_NE(r.failure_reason.find("the fixed region selects no node"), std::string::npos) << r.failure_reason;
}

// The loaded box [L - 0.01, L + 1] holds the beam's end face only while the
// end lands on a node layer of the 2 mm FEM grid within it: L = 100 puts it
// at x = 100, L = 100.5 voxelises the beam to x = 100 (the cell [100, 102]
// has its centre outside), which the box misses.
TEST(DesignFem, LoadedRegionMissingAtOneSampleOnlyInvalidatesThatSample) {
  design::Design d =
      design::LoadDesign(TempDesign(Cantilever(100, 10, 10, 2, 1000, 0.25, "[[-1, -1, -1], [0.01, 11, 11]]")));
  design::SampleResult hit = Evaluate(d, "L=100");
  EXPECT_TRUE(hit.valid) << hit.failure << ": " << hit.failure_reason;
  design::SampleResult miss = Evaluate(d, "L=100.5");
  EXPECT_FALSE(miss.valid);
  EXPECT_EQ(miss.failure, design::kLoadCaseMissesSolid);
  EXPECT_NE(miss.failure_reason.find("the loaded region selects no boundary face"), std::string::npos)
      << miss.failure_reason;
}

// `element: q1` selects the plain trilinear element, which locks in bending:
// 5 elements through the depth give a visibly stiffer beam than the default
// incompatible modes. An unknown element is a one-line input error.
TEST(DesignFem, ElementChoice) {
  std::string text = Cantilever(100, 10, 10, 2, 1000, 0.25, "[[-1, -1, -1], [0.01, 11, 11]]");
  const double im = MaxDisplacement(FemOutcome(Evaluate(design::LoadDesign(TempDesign(text)))));
  const double q1 = MaxDisplacement(FemOutcome(Evaluate(design::LoadDesign(TempDesign(text + "    element: q1\n")))));
  EXPECT_LT(q1, 0.98 * im) << "q1 " << q1 << " incompatible modes " << im;
  ExpectOneLineError(text + "    element: q2\n", "'element' must be incompatible_modes or q1");
}

TEST(DesignFem, FixedRegionNeedsTwoCorners) {
  ExpectOneLineError(Cantilever(100, 10, 10, 2, 1000, 0.25, "[[0, 0, 0], [1, 1, 1], [2, 2, 2]]"), "two corners");
}

TEST(DesignFem, TooManyElementsIsAnInputError) {
  // 216 000 voxel hexahedra of 1 mm fill a 60 mm cube (limit 200 000).
  ExpectOneLineError(Cantilever(60, 60, 60, 1, 1000, 0.25, "[[-1, -1, -1], [0.01, 61, 61]]"), "too small");
  // 0.05 mm voxels: 1.7e9 cells over the bounding box, refused before sampling.
  ExpectOneLineError(Cantilever(60, 60, 60, 0.05, 1000, 0.25, "[[-1, -1, -1], [0.01, 61, 61]]"), "too small");
}
