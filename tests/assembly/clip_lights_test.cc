// The clip-lights design family: parameter ranges and the kinematics of the
// turnbuckle extension.
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "fabatlas/testing/paths.h"

#include "fabatlas/assembly/clip_lights.h"
#include "fabatlas/error.h"

using namespace fabatlas::assembly;

namespace {
std::string Lib() { return fabatlas::testing::SourceDir().string() + "/configs/assemblies/parts.yaml"; }
}  // namespace

TEST(AssemblyClipLights, RejectsParametersOutsideTheirRanges) {
  EXPECT_THROW(BuildClipLights({0, 10, RingSize::kXS}, Lib()), fabatlas::InputError);
  EXPECT_THROW(BuildClipLights({5, 10, RingSize::kXS}, Lib()), fabatlas::InputError);
  EXPECT_THROW(BuildClipLights({2, 46, RingSize::kXS}, Lib()), fabatlas::InputError);
  const Program p = BuildClipLights({3, 10, RingSize::kM}, Lib());
  EXPECT_EQ(p.instances.size(), 1u + 1u + 2u * 3u + 1u);  // ceiling, hanger, 3 pairs, light
  EXPECT_EQ(p.connections.size(), 2u * 3u + 2u);
  // ParamTurnbuckle hooks at y = ±(43.5 + e/2) (PARTS.md §3.1).
  EXPECT_NEAR(p.library.parts.at("ParamTurnbuckle").primitives[0].frame.position.y(), 48.5, 1e-12);
}

TEST(AssemblyClipLights, ExtensionLowersTheLightByItsLength) {
  // A hanging chain is vertical after relaxation, so extending the single
  // turnbuckle by 20 mm lowers the light by 20 mm.
  const ClipLightsResult a = EvaluateClipLights({1, 0, RingSize::kS}, Lib());
  const ClipLightsResult b = EvaluateClipLights({1, 20, RingSize::kS}, Lib());
  ASSERT_TRUE(a.feasible);
  ASSERT_TRUE(b.feasible);
  const double za = a.summary.poses.back().translation().z();
  const double zb = b.summary.poses.back().translation().z();
  EXPECT_NEAR(za - zb, 20, 2);
  EXPECT_GT(a.target_deviation_mm, 0);
}
