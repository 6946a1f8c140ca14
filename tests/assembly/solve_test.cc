// Two-step solve of the FabHacks Table 5 examples (programs and parts from
// data/fabhacks/PARTS.md) and the Fig. 9 behaviour. The paper built every
// Table 5 example and shows it working (Figs. 1, 5, 8, 10, 12): each must be
// feasible and must not fall apart; the one-eyehook soap bottle of Fig. 9
// must.
#include <cmath>
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
  const char* all[] = {"demo",          "toothbrush_holder",  "charger_holder", "soap_bottle_holder", "mug_hanger",
                       "bird_feeder",   "paper_towel_holder", "diaper_caddy",   "bathroom_basket",    "clip_lights_1",
                       "clip_lights_2", "clip_lights_3",      "clip_lights_4",  "reading_nook"};
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
  EXPECT_EQ(stable, 14);
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

namespace {
// One S-hook hanging from the middle of an open 500 mm rod tilted `tilt_deg`
// above the horizontal (R = Rz(90)·Rx(90 − tilt) turns the rod's z axis to
// (cos tilt, 0, sin tilt)). Its load is its weight, vertical, so the angle of
// the load past the rod's normal plane is the tilt.
SolveSummary HookOnTiltedRod(double tilt_deg, bool friction) {
  const std::string a = std::to_string(90 - tilt_deg);
  const Program p =
      ParseProgram("start_with: {name: env, part: DemoRod, frame: [[0, 0, 400], [" + a +
                       ", 0, 90]]}\n"
                       "end_with: {name: dh, part: DoubleHook, frame: [[0, 0, 370], [0, 0, 0]]}\n"
                       "steps:\n  - {attach: dh.hook1, to: env.rod}\n",
                   "tilted_rod.yaml", fabatlas::testing::SourceDir().string() + "/configs/assemblies/parts.yaml");
  SolveOptions o;
  o.slide_friction = friction;
  return SolveAssembly(p, o);
}
}  // namespace

TEST(AssemblySolve, StaticFrictionHoldsAHookOnARodTiltedLessThanTheFrictionAngle) {
  // Static friction along rods (docs/assembly.md): held while the load is
  // within friction_angle_deg (20°) of the rod's normal plane.
  for (double tilt : {5.0, 15.0}) {
    const SolveSummary s = HookOnTiltedRod(tilt, true);
    ASSERT_TRUE(s.feasible);
    ASSERT_EQ(s.slides.size(), 1u);
    EXPECT_EQ(s.slides[0].where, "env.rod.t (dh.hook1)");
    EXPECT_NEAR(s.slides[0].load_angle_deg, tilt, 0.1);
    EXPECT_TRUE(s.slides[0].held);
    EXPECT_TRUE(s.stable) << tilt << ": " << Join(s.falls_apart);
    // Without friction (the paper's model) the same hook runs off the rod's lower, open end.
    const SolveSummary f = HookOnTiltedRod(tilt, false);
    EXPECT_FALSE(f.stable) << tilt;
    ASSERT_EQ(f.falls_apart.size(), 1u);
    EXPECT_EQ(f.falls_apart[0], "env.rod.t at min");
  }
  const SolveSummary s = HookOnTiltedRod(25, true);
  ASSERT_EQ(s.slides.size(), 1u);
  EXPECT_NEAR(s.slides[0].load_angle_deg, 25, 0.1);
  EXPECT_FALSE(s.slides[0].held);
  EXPECT_FALSE(s.stable);
  ASSERT_EQ(s.falls_apart.size(), 1u);
  EXPECT_EQ(s.falls_apart[0], "env.rod.t at min");
}

TEST(AssemblySolve, DemoSHookStaysOnTheBarUnlessFrictionless) {
  // FabHacks Fig. 10: without friction "the S-hook and ring could slide to
  // either end of the hanger's rod"; they do (t = 1, 39 mm from where step 1
  // put them). With static friction the S-hook's load is its chain's weight,
  // vertical, so its angle past the bar's normal plane is the bar's tilt once
  // the hanger has swung (7.7°), inside the friction angle: it stays.
  const Program p = LoadProgram(Config("demo"));
  const SolveSummary s = SolveAssembly(p);
  ASSERT_TRUE(s.stable) << Join(s.falls_apart);
  ASSERT_EQ(s.slides.size(), 2u);
  EXPECT_EQ(s.slides[1].where, "hanger.rod.t (dh.hook1)");
  EXPECT_TRUE(s.slides[1].held);
  const Eigen::Vector3d bar = s.poses[1].linear() * ToIsometry(p.PartOf(1).Find("rod")->frame).linear().col(2);
  const double tilt = std::asin(std::abs(bar.z())) * 180 / M_PI;
  EXPECT_NEAR(s.slides[1].load_angle_deg, tilt, 0.05);
  EXPECT_LT(tilt, 20);
  EXPECT_GT(s.params[1][0], 0.85);
  EXPECT_LT(s.params[1][0], 0.95);
  SolveOptions frictionless;
  frictionless.slide_friction = false;
  const SolveSummary f = SolveAssembly(p, frictionless);
  ASSERT_TRUE(f.stable) << Join(f.falls_apart);  // the bar is clamped at its ends
  EXPECT_NEAR(f.params[1][0], 1.0, 1e-6);
}

namespace {
// The reading nook as parts.yaml has it (rod2 closed at both ends, as
// readingroom.stl shows: rod_ends_test) or with rod2's ends as the published
// data leaves them (is_open's default: both open).
Program Nook(bool published_peg_ends) {
  Program p = LoadProgram(Config("reading_nook"));
  if (published_peg_ends)
    for (Connection& c : p.connections)
      if (p.instances[c.part_a].name == "room" && c.primitive_a == "rod2")
        for (ParamSpec& s : c.params_a) s.blocked_min = s.blocked_max = false;
  return p;
}
// rod2's t (the first parameter of the connection that has room.rod2 on side a).
double PegT(const Program& p, const SolveSummary& s) {
  for (size_t i = 0; i < p.connections.size(); ++i)
    if (p.instances[p.connections[i].part_a].name == "room" && p.connections[i].primitive_a == "rod2")
      return s.params[i][0];
  return -1;
}
}  // namespace

TEST(AssemblySolve, ReadingNookHookIsPulledAgainstTheBodyAtThePegsEnd) {
  // The turnbuckle's hook hangs at t = 0 of the wall peg rod2 (the room side,
  // where step 1 needs it for the published hoop frame). Held by friction
  // there, the relaxed structure pulls it 35–36° past the peg's normal plane
  // towards t = 0, beyond the 20° friction angle; let go, it stays at t = 0,
  // pressed against the scanned body the peg runs into there. Were that end
  // open (the published default), it would fall off (docs/assembly-notes.md "The
  // reading nook against the published method").
  const Program p = Nook(false);
  const SolveSummary s = SolveAssembly(p);
  ASSERT_TRUE(s.feasible);
  ASSERT_EQ(s.slides.size(), 1u);
  EXPECT_EQ(s.slides[0].where, "room.rod2.t (tb.hook1)");
  EXPECT_FALSE(s.slides[0].held);
  EXPECT_GT(s.slides[0].load_angle_deg, 30);
  EXPECT_TRUE(s.stable) << Join(s.falls_apart);
  EXPECT_NEAR(PegT(p, s), 0, 1e-9);
  const SolveSummary open = SolveAssembly(Nook(true));
  EXPECT_FALSE(open.stable);
  ASSERT_EQ(open.falls_apart.size(), 1u);
  EXPECT_EQ(open.falls_apart[0], "room.rod2.t at min");
}

TEST(AssemblySolve, ReadingNookUnderThePapersRelaxation) {
  // The paper's model (FabHacks Eq. 2: no friction) relaxed as the reference
  // implementation relaxes it, with an active set holding every parameter
  // that reaches a bound (its active-set Newton). Bounded LM alone stops
  // where the ring links' flex angles reach 45°; held there, the structure
  // relaxes on by 0.66 J and the hoop, hung from two nearly opposite points
  // of its rim (the two rod1 chains meet it 3° apart, the turnbuckle chain
  // 186° away), turns about that diameter, > 60° from the published frame.
  // The turnbuckle's hook stays at the peg's t = 0 end with the energy
  // falling past it: held there by the body the peg runs into (were that end
  // open it would fall off, as in the test above; docs/assembly-notes.md "The
  // reading nook against the published method").
  SolveOptions o;
  o.slide_friction = false;
  o.relaxation_active_set = true;
  const Program p = Nook(false);
  const SolveSummary s = SolveAssembly(p, o);
  ASSERT_TRUE(s.feasible);
  EXPECT_GT(s.final_target_error_deg, 60);
  EXPECT_TRUE(s.stable) << Join(s.falls_apart);
  EXPECT_NEAR(PegT(p, s), 0, 1e-9);
}
