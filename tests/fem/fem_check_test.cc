// The design-level FEM check (Fab Forms sandal; docs/fem.md): a short
// thick block passes, a slender cantilever under the same load fails.
#include "fabatlas/fem/fem_check.h"

#include <gtest/gtest.h>

namespace fabatlas::fem {
namespace {

VoxelSolid Block(int nx, int ny, int nz, double h) {
  VoxelSolid s;
  s.voxel_size = h;
  s.dims = {nx, ny, nz};
  s.occupied.assign(static_cast<std::size_t>(nx) * ny * nz, 1);
  return s;
}

// Fixed at the x = 0 face, loaded on the x = length face with `force`.
FemLoadCase EndLoad(double length, const Vec3& force) {
  FemLoadCase lc;
  lc.fixed_region.push_back({{-0.01, -1e3, -1e3}, {0.01, 1e3, 1e3}});
  lc.loaded_region.push_back({{length - 0.01, -1e3, -1e3}, {length + 0.01, 1e3, 1e3}});
  lc.total_force = force;
  lc.material = Material::FromYoungPoisson(100.0, 0.3);  // MPa, a soft printed elastomer
  return lc;
}

TEST(FemCheck, ShortThickBlockPasses) {
  // 8 x 8 x 8 mm block, 1 mm voxels, 0.5 N sideways on its free end.
  const FemLoadCase lc = EndLoad(8.0, {0, 0, -0.5});
  FemCheckOptions opt;
  opt.max_displacement = 0.5;  // mm
  const FemCheckResult r = RunFemCheck(Block(8, 8, 8, 1.0), lc, opt);
  EXPECT_TRUE(r.passed) << r.reason;
  EXPECT_TRUE(r.converged);
  EXPECT_TRUE(r.reason.empty());
  EXPECT_EQ(r.num_elements, 512);
  // Peer value: CalculiX 2.20 (calculix-ccx) on the same mesh and load,
  // C3D8I, Neo-Hookean, NLGEOM: max |u| = 0.00481713 mm (C3D8: 0.00476134);
  // bench/fem/calculix_cantilever ... fem_check_test writes and runs it.
  // Beam theory is only an estimate for a stubby block (bending
  // PL^3/(3EI) = 2.5e-3 mm plus Timoshenko shear PL/(kGA) = 1.95e-3 mm).
  RecordProperty("max_displacement", std::to_string(r.max_displacement));
  EXPECT_NEAR(r.max_displacement, 0.00481713, 0.01 * 0.00481713);
}

TEST(FemCheck, SlenderCantileverFailsWithReason) {
  // 60 x 3 x 3 mm beam, same load: Euler-Bernoulli PL^3/(3EI) = 53 mm in
  // the linear theory, far beyond the 0.5 mm threshold. Large rotation:
  // peer value CalculiX C3D8I on the same mesh and load (as above),
  // max |u| = 37.0545 mm (C3D8, which locks with 3 elements through the
  // depth: 35.8582, what Q1 gives here).
  const FemLoadCase lc = EndLoad(60.0, {0, 0, -0.5});
  FemCheckOptions opt;
  opt.max_displacement = 0.5;
  const FemCheckResult r = RunFemCheck(Block(60, 3, 3, 1.0), lc, opt);
  EXPECT_FALSE(r.passed);
  ASSERT_TRUE(r.converged) << r.reason;
  RecordProperty("max_displacement", std::to_string(r.max_displacement));
  EXPECT_NEAR(r.max_displacement, 37.0545, 0.005 * 37.0545);
  EXPECT_NE(r.reason.find("exceeds the threshold 0.5 mm"), std::string::npos) << r.reason;
}

TEST(FemCheck, StrainLimitIsChecked) {
  const FemLoadCase lc = EndLoad(8.0, {0, 0, -0.5});
  FemCheckOptions opt;
  opt.max_displacement = 0.5;
  opt.max_strain = 1e-6;
  const FemCheckResult r = RunFemCheck(Block(8, 8, 8, 1.0), lc, opt);
  EXPECT_FALSE(r.passed);
  EXPECT_NE(r.reason.find("strain"), std::string::npos) << r.reason;
  EXPECT_GT(r.max_strain, 1e-6);
}

// A region that selects nothing on this solid fails the check with the
// reason (for a parametric design it depends on the sample's geometry).
TEST(FemCheck, RegionsThatSelectNothingFailTheCheck) {
  FemLoadCase lc = EndLoad(8.0, {0, 0, -0.5});
  lc.fixed_region = {{{100, 100, 100}, {101, 101, 101}}};
  FemCheckResult r = RunFemCheck(Block(8, 8, 8, 1.0), lc);
  EXPECT_FALSE(r.passed);
  EXPECT_TRUE(r.empty_load_case);
  EXPECT_EQ(r.reason, "the fixed region selects no node of the solid");
  lc = EndLoad(8.0, {0, 0, -0.5});
  lc.loaded_region = {{{3.5, 3.5, 3.5}, {4.5, 4.5, 4.5}}};  // interior: no boundary face
  r = RunFemCheck(Block(8, 8, 8, 1.0), lc);
  EXPECT_FALSE(r.passed);
  EXPECT_TRUE(r.empty_load_case);
  EXPECT_EQ(r.reason, "the loaded region selects no boundary face of the solid");
  VoxelSolid nothing = Block(8, 8, 8, 1.0);
  nothing.occupied.assign(nothing.occupied.size(), 0);
  r = RunFemCheck(nothing, EndLoad(8.0, {0, 0, -0.5}));
  EXPECT_TRUE(r.empty_load_case);
  EXPECT_FALSE(r.passed);
  // A good load case is not empty.
  EXPECT_FALSE(RunFemCheck(Block(8, 8, 8, 1.0), EndLoad(8.0, {0, 0, -0.5})).empty_load_case);
}

}  // namespace
}  // namespace fabatlas::fem
