// Two-step solve of the FabHacks Table 5 examples (programs and parts from
// data/fabhacks/PARTS.md) and the Fig. 9 behaviour. The paper built every
// Table 5 example and shows it working (Figs. 1, 5, 8, 10, 12): each must be
// feasible and must not fall apart; the one-eyehook soap bottle of Fig. 9
// must.
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "fabatlas/testing/paths.h"

#include "fabatlas/assembly/precheck.h"
#include "fabatlas/assembly/program.h"
#include "fabatlas/assembly/solve.h"

using namespace fabatlas::assembly;

namespace {
std::string Config(const std::string& name) {
  return fabatlas::testing::SourceDir().string() + "/configs/assemblies/" + name + ".yaml";
}
std::string Join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += x + "; ";
  return s;
}
}  // namespace

TEST(AssemblySolve, SoapBottleOneEyehookFallsTwoHold) {
  // FabHacks Fig. 9: same target for both programs; after relaxation under
  // gravity the one-eyehook basket swings about its single hook (top row) and
  // the bottle standing in it no longer stays, the two-eyehook one holds.
  const SolveSummary one = SolveAssembly(LoadProgram(Config("soap_bottle_holder_one_hook")));
  const SolveSummary two = SolveAssembly(LoadProgram(Config("soap_bottle_holder")));
  ASSERT_TRUE(one.feasible);
  ASSERT_TRUE(two.feasible);
  // Step 1 brings both bottles to the target.
  EXPECT_LT(one.step1_target_error_mm, 5);
  EXPECT_LT(two.step1_target_error_mm, 5);
  EXPECT_FALSE(one.stable);
  ASSERT_FALSE(one.falls_apart.empty());
  EXPECT_NE(one.falls_apart[0].find("bottle.surface"), std::string::npos) << one.falls_apart[0];
  EXPECT_GT(one.relax_rotation_deg, 30);
  EXPECT_TRUE(two.stable) << Join(two.falls_apart);
  EXPECT_LT(two.final_target_error_mm, one.final_target_error_mm / 10);
}

TEST(AssemblySolve, TableFiveExamplesAreFeasibleAndStable) {
  const char* all[] = {"demo", "toothbrush_holder", "charger_holder", "soap_bottle_holder", "mug_hanger",
                       "bird_feeder", "paper_towel_holder", "diaper_caddy", "bathroom_basket", "clip_lights_1",
                       "clip_lights_2", "clip_lights_3", "clip_lights_4"};
  int stable = 0;
  for (const char* name : all) {
    const Program p = LoadProgram(Config(name));
    const PrecheckSummary pre = Precheck(p);
    EXPECT_TRUE(pre.ok) << name << ": " << (pre.issues.empty() ? "" : pre.issues[0].message);
    const SolveSummary s = SolveAssembly(p);
    EXPECT_TRUE(s.feasible) << name;
    EXPECT_TRUE(s.stable) << name << ": " << Join(s.falls_apart);
    stable += s.feasible && s.stable;
  }
  EXPECT_EQ(stable, 13);
}

TEST(AssemblySolve, PublishedTargetsAreReachedInStepOne) {
  // With the published part data the targets of these examples are reached
  // by step 1 (the objective weighs 1 mm like 1 degree, PARTS.md §2.1). The
  // bathroom basket's is reached only from the chain-by-chain start (from the
  // defaults and the Halton starts step 1 ends 47.6 mm / 13.4° away, its
  // eyehooks tilted 69° to reach the handle).
  for (const char* name : {"toothbrush_holder", "charger_holder", "soap_bottle_holder", "paper_towel_holder",
                           "diaper_caddy", "demo", "bathroom_basket"}) {
    const SolveSummary s = SolveAssembly(LoadProgram(Config(name)));
    ASSERT_TRUE(s.feasible) << name;
    EXPECT_LT(s.step1_target_error_mm, 2) << name;
    EXPECT_LT(s.step1_target_error_deg, 2) << name;
  }
}

TEST(AssemblySolve, ChainByChainStartBringsTheReadingNookToItsTarget) {
  // FabHacks Table 5 ★: the reading nook was solved from initial guesses
  // computed chain by chain. Without that start step 1 ends 93 mm / 64° from
  // the published hoop frame (the defaults are the only start of 16 that
  // closes both cycles); with it, within 26 mm / 4° — the hoop is then at the
  // end of the turnbuckle chain's reach (574.6 mm of chain for the 572.8 mm
  // from rod2's tip to the nearest point of the hoop at the target).
  const Program p = LoadProgram(Config("reading_nook"));
  SolveOptions without;
  without.chain_start = -1;
  without.relax = false;
  const SolveSummary a = SolveAssembly(p, without);
  SolveOptions with;
  with.relax = false;
  const SolveSummary b = SolveAssembly(p, with);
  ASSERT_TRUE(a.feasible);
  ASSERT_TRUE(b.feasible);
  EXPECT_GT(a.step1_target_error_mm, 80);
  EXPECT_LT(b.step1_target_error_mm, 26);
  EXPECT_LT(b.step1_target_error_deg, 4);
}
