// Pre-checks (FabHacks, 4.3.1–4.3.2): connectivity, closed primitives, and the
// polygon-inequality quick reject of cycles before any solve.
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "fabatlas/testing/paths.h"

#include "fabatlas/assembly/precheck.h"
#include "fabatlas/assembly/program.h"
#include "fabatlas/assembly/solve.h"

using namespace fabatlas::assembly;

namespace {
std::string Lib() { return fabatlas::testing::SourceDir().string() + "/configs/assemblies/parts.yaml"; }
std::string Mesh() { return DefaultMeshDir(); }
CycleLink L(double lo, double hi) { return {"p", lo, hi}; }
}  // namespace

TEST(AssemblyPolygon, TriangleInequality) {
  // Rigid links 1, 1, 3 cannot close; 1, 1, 2 close (degenerate); 3 fits if it may shrink to 2.
  EXPECT_FALSE(PolygonInequalityFeasible({L(1, 1), L(1, 1), L(3, 3)}));
  EXPECT_TRUE(PolygonInequalityFeasible({L(1, 1), L(1, 1), L(2, 2)}));
  EXPECT_TRUE(PolygonInequalityFeasible({L(1, 1), L(1, 1), L(2, 3)}));
  EXPECT_FALSE(PolygonInequalityFeasible({L(10, 12), L(0, 3), L(0, 3), L(0, 3)}));
  EXPECT_TRUE(PolygonInequalityFeasible({L(10, 12), L(0, 3), L(0, 3), L(0, 3)}, 1.0));
}

TEST(AssemblyPrecheck, ClosedAndUnconnectablePairsRejected) {
  // Ring on the basket's ring-less rod is fine; a rod on a rod (Table 1) and
  // a ring on a ring (both closed) are not.
  const Program p = ParseProgram(
      "start_with: {name: door, part: DoorRod, frame: [[0,0,500],[90,0,90]]}\n"
      "parts: {r1: RingXS, r2: RingS}\n"
      "end_with: {name: bottle, part: SoapBottle, frame: [[0,0,0],[0,0,0]]}\n"
      "steps:\n"
      "  - {attach: r1.ring, to: door.door}\n"
      "  - {attach: r2.ring, to: r1.ring}\n"
      "  - {attach: bottle.rod, to: door.door}\n",
      "closed.yaml", Lib(), Mesh());
  const PrecheckSummary s = Precheck(p);
  EXPECT_FALSE(s.ok);
  ASSERT_EQ(s.issues.size(), 2u);
  EXPECT_EQ(s.issues[0].failure, PrecheckFailure::kBothClosed);
  EXPECT_EQ(s.issues[0].message.rfind("closed.yaml:6:", 0), 0u) << s.issues[0].message;
  EXPECT_EQ(s.issues[1].failure, PrecheckFailure::kNotConnectable);
}

TEST(AssemblyPrecheck, CriticalDimensionExhausted) {
  // Rings XS have a 33.3 mm arc radius; a 38.5 mm-radius bottle rod does not fit.
  const Program p = ParseProgram(
      "start_with: {name: door, part: DoorRod, frame: [[0,0,500],[90,0,90]]}\n"
      "end_with: {name: ring, part: RingXS, frame: [[0,0,0],[0,0,0]]}\n"
      "parts: {bottle: SoapBottle}\n"
      "steps:\n"
      "  - {attach: ring.ring, to: door.door}\n"
      "  - {attach: bottle.rod, to: ring.ring}\n",
      "crit.yaml", Lib(), Mesh());
  const PrecheckSummary s = Precheck(p);
  ASSERT_FALSE(s.ok);
  EXPECT_EQ(s.issues[0].failure, PrecheckFailure::kCriticalDimension);
}

TEST(AssemblyPrecheck, CycleThatCannotCloseIsRejectedBeforeSolving) {
  // The two-eyehook basket of FabHacks Fig. 7, but the eyehooks hang from two
  // rods 2 m apart: eyehooks (< 100 mm) + basket (< 300 mm) cannot span them.
  const Program p = ParseProgram(
      "start_with: {name: env, part: ClosetRods, frame: [[0,0,0],[0,0,0]]}\n"
      "parts: {e1: HookEyeLeft, e2: HookEyeLeft, basket: Basket}\n"
      "end_with: {name: basket, frame: [[0,0,0],[0,0,0]]}\n"
      "steps:\n"
      "  - {attach: e1.ring, to: env.rod1}\n"
      "  - {attach: e2.ring, to: env.rod2}\n"
      "  - {attach: basket.rod1, to: e1.hook}\n"
      "  - {connect: e2.hook, with: basket.rod2}\n",
      "near.yaml", Lib(), Mesh());
  // ClosetRods pieces are 350 mm apart (centres at y = ±175): this closes.
  EXPECT_TRUE(Precheck(p).ok);
  ASSERT_EQ(Precheck(p).cycles.size(), 1u);
  EXPECT_EQ(Precheck(p).cycles[0].size(), 4u);

  Program far = p;
  far.library.parts["ClosetRods"].primitives[0].frame.position = {0, 1000, 0};
  far.library.parts["ClosetRods"].primitives[1].frame.position = {0, -1000, 0};
  const PrecheckSummary s = Precheck(far);
  ASSERT_FALSE(s.ok);
  EXPECT_EQ(s.issues[0].failure, PrecheckFailure::kCycleCannotClose);
  EXPECT_NE(s.issues[0].message.find("polygon inequality"), std::string::npos) << s.issues[0].message;
  const SolveSummary sol = SolveAssembly(far);
  EXPECT_FALSE(sol.prechecks_passed);
  EXPECT_EQ(sol.starts_tried, 0);  // rejected before any Ceres solve
}
