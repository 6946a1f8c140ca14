// The solve's analytic forward-kinematics Jacobian equals Ceres autodiff of
// the same residuals on every Table 5 program, at several starts, all phases.
#include <algorithm>
#include <string>

#include <gtest/gtest.h>

#include "fabatlas/testing/paths.h"

#include "fabatlas/assembly/program.h"
#include "solve_internal.h"

using namespace fabatlas::assembly;

TEST(AssemblyJacobian, AnalyticEqualsAutodiff) {
  const char* all[] = {
      "demo",          "toothbrush_holder", "charger_holder",     "soap_bottle_holder", "soap_bottle_holder_one_hook",
      "mug_hanger",    "bird_feeder",       "paper_towel_holder", "diaper_caddy",       "bathroom_basket",
      "clip_lights_1", "clip_lights_2",     "clip_lights_3",      "clip_lights_4",      "reading_nook"};
  int checked = 0;
  for (const char* name : all) {
    const Program p = LoadProgram(fabatlas::testing::SourceDir().string() + "/configs/assemblies/" + name + ".yaml");
    for (int start = 0; start < 4; ++start)
      for (int phase = 0; phase < 3; ++phase) {
        const internal::JacobianCheck c = internal::CheckJacobian(p, start, phase);
        if (c.residuals == 0) continue;  // e.g. feasibility of a program without cycles
        ++checked;
        EXPECT_GT(c.max_entry, 0) << name << " start " << start << " phase " << phase;
        EXPECT_LE(c.max_error, 1e-9 * std::max(1.0, c.max_entry))
            << name << " start " << start << " phase " << phase << ": largest entry " << c.max_entry;
        EXPECT_LE(c.max_residual_error, 1e-9) << name << " start " << start << " phase " << phase;
      }
  }
  EXPECT_GE(checked, 14 * 4 * 2);
}
