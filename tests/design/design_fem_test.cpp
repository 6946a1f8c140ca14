// The fem check of design files (seed 001 Sec. 8, docs/design-format.md):
// the sandal example, a cantilever against Euler-Bernoulli beam theory, and
// one-line errors for bad FEM arguments.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

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
}

TEST(DesignFem, ThinTallHeelDeformsTooMuch) {
  design::Design d = Sandal();
  design::SampleResult r = Evaluate(d, "heel_height=80,heel_thickness=8");
  const design::CheckOutcome& fem = FemOutcome(r);
  std::printf("sandal thin tall heel: %s\n", fem.reason.c_str());
  EXPECT_FALSE(r.valid);
  EXPECT_EQ(r.failure, design::kTooMuchDeformation);
  EXPECT_FALSE(fem.passed);
  EXPECT_NE(r.failure_reason.find("max displacement"), std::string::npos) << r.failure_reason;
}
