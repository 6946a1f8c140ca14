// Part library: frames, parametrised connector frames (PARTS.md §1 formulas),
// alignment frames by key (PARTS.md §2.2), mesh mass properties (EXAMPLES.md
// volumes), YAML errors.
#include <cmath>
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "fabatlas/testing/paths.h"

#include "fabatlas/assembly/mass_properties.h"
#include "fabatlas/assembly/part_library.h"
#include "fabatlas/assembly/program.h"
#include "fabatlas/error.h"

using namespace fabatlas::assembly;

namespace {
std::string Shared() { return DefaultMeshDir() + "/../../.."; }
std::string Source() { return fabatlas::testing::SourceDir().string(); }

Primitive Hook(double arc_radius, double arc_angle, double thickness) {
  Primitive p;
  p.name = "hook";
  p.type = PrimitiveType::kHook;
  p.shape = {{"arc_radius", arc_radius}, {"arc_angle", arc_angle}, {"thickness", thickness}};
  return p;
}
}  // namespace

TEST(AssemblyFrame, EulerIsRzRyRx) {
  // Rx(90) maps y to z; Rz(90) maps x to y; R = Rz(c)·Ry(b)·Rx(a).
  EXPECT_TRUE((EulerToRotation({90, 0, 0}) * Eigen::Vector3d::UnitY()).isApprox(Eigen::Vector3d::UnitZ(), 1e-12));
  EXPECT_TRUE((EulerToRotation({0, 0, 90}) * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  // Rz(90)·Rx(90) applied to y: Rx sends y to z, Rz keeps z.
  EXPECT_TRUE((EulerToRotation({90, 0, 90}) * Eigen::Vector3d::UnitY()).isApprox(Eigen::Vector3d::UnitZ(), 1e-12));
  EXPECT_NEAR(RotationAngleDeg(EulerToRotation({0, 0, 30}), Eigen::Matrix3d::Identity()), 30, 1e-9);
}

TEST(AssemblyPrimitive, HookFrameFollowsArc) {
  // r' = arc_radius − thickness = 14; theta = 90° puts the contact at (0, −r', 0)
  // with R = Rx(−90) (EXAMPLES.md hook parametrisation).
  const Primitive h = Hook(19, 210, 5);
  const Eigen::Isometry3d m = ConnectorFrame(h, {90});
  EXPECT_TRUE(m.translation().isApprox(Eigen::Vector3d(0, -14, 0), 1e-12));
  EXPECT_TRUE(m.linear().isApprox(EulerToRotation({-90, 0, 0}), 1e-12));
  EXPECT_TRUE(ConnectorFrame(h, {0}).translation().isApprox(Eigen::Vector3d(0, 0, -14), 1e-12));
  ASSERT_EQ(h.Params().size(), 1u);
  EXPECT_EQ(h.Params()[0].max, 210);
  EXPECT_EQ(h.Params()[0].kind, ParamKind::kBoundedAndOpen);
}

TEST(AssemblyPrimitive, RodFrameSlidesAlongAxis) {
  Primitive r;
  r.type = PrimitiveType::kRod;
  r.shape = {{"length", 500}, {"radius", 5}};
  EXPECT_TRUE(ConnectorFrame(r, {1.0, 90}).translation().isApprox(Eigen::Vector3d(0, 5, 250), 1e-12));
  EXPECT_TRUE(ConnectorFrame(r, {0.0, 90}).translation().isApprox(Eigen::Vector3d(0, 5, -250), 1e-12));
  EXPECT_EQ(r.Params()[0].kind, ParamKind::kBoundedAndOpen);
  r.clamped = true;  // is_open false: sliding off the end is impossible
  EXPECT_EQ(r.Params()[0].kind, ParamKind::kBoundedAndClamped);
  // RodCtl: one parameter, on the centre line (PARTS.md §1.1).
  r.ctl = true;
  ASSERT_EQ(r.Params().size(), 1u);
  EXPECT_TRUE(ConnectorFrame(r, {1.0}).translation().isApprox(Eigen::Vector3d(0, 0, 250), 1e-12));
  EXPECT_EQ(r.ClassName(true), "RodCtl");
  EXPECT_EQ(r.ClassName(false), "Rod");
}

TEST(AssemblyPrimitive, HemisphereAndSurfaceFollowPartsMd) {
  // Hemisphere defaults (θ, φ) = (180, 180) give the bottom pole (0, 0, −R)
  // (PARTS.md §1.8); a surface frame sits on top of its 0.1 mm plate (§1.7).
  Primitive h;
  h.type = PrimitiveType::kHemisphere;
  h.shape = {{"radius", 9}};
  EXPECT_TRUE(ConnectorFrame(h, {180, 180, 0}).translation().isApprox(Eigen::Vector3d(0, 0, -9), 1e-12));
  Primitive s;
  s.type = PrimitiveType::kSurface;
  s.shape = {{"width", 100}, {"length", 200}};
  EXPECT_TRUE(ConnectorFrame(s, {0, 1, 0}).translation().isApprox(Eigen::Vector3d(100, 50, 0.05), 1e-12));
}

TEST(AssemblyPrimitive, AlignmentFramesByKeyAndFlip) {
  // PARTS.md §2.2 and the flipped values it lists.
  EXPECT_TRUE(AlignmentOffset("Rod_Hook", false).isApprox(EulerToRotation({180, 0, 90}), 1e-12));
  EXPECT_TRUE(AlignmentOffset("Rod_HookFlex", true).isApprox(EulerToRotation({180, 0, -90}), 1e-12));
  EXPECT_TRUE(AlignmentOffset("RingCtl_RodCtl", false).isApprox(EulerToRotation({0, 0, 90}), 1e-12));
  EXPECT_TRUE(AlignmentOffset("Edge_Clip", false).isApprox(EulerToRotation({0, -90, -90}), 1e-12));
  EXPECT_TRUE(AlignmentOffset("Edge_Clip", true).isApprox(EulerToRotation({0, 90, 90}), 1e-12));
  EXPECT_TRUE(AlignmentOffset("Rod_Clip", true).isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  EXPECT_TRUE(AlignmentOffset("HookFlex_Tube", true).isApprox(EulerToRotation({0, 0, -90}), 1e-12));
  EXPECT_TRUE(AlignmentOffset("Surface_Surface", true).isApprox(EulerToRotation({180, 0, 0}), 1e-12));
  EXPECT_TRUE(AlignmentOffset("Ring_Ring", false).isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  EXPECT_TRUE(AlignmentOffset("Tube_TubeCtl", false).isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  EXPECT_TRUE(CanConnect(PrimitiveType::kHook, PrimitiveType::kRod));
  EXPECT_FALSE(CanConnect(PrimitiveType::kRod, PrimitiveType::kRod));
}

TEST(AssemblyMass, MeshVolumesMatchReference) {
  // EXAMPLES.md part masses (mesh volume, density 1) and centres of mass.
  const std::string d = Shared() + "/data/fabhacks/meshes/";
  EXPECT_NEAR(ComputeMassProperties(d + "ringXS.off").volume_mm3, 7054, 0.005 * 7054);
  EXPECT_NEAR(ComputeMassProperties(d + "ringL.off").volume_mm3, 13409, 0.005 * 13409);
  const MassProperties he = ComputeMassProperties(d + "hookeyeleft.obj");
  EXPECT_NEAR(he.volume_mm3, 17222, 0.005 * 17222);
  EXPECT_NEAR(he.centre_of_mass.z(), -30.1, 0.1);
  EXPECT_NEAR(ComputeMassProperties(d + "basket.obj").centre_of_mass.z(), 100.5, 0.1);
  EXPECT_NEAR(ComputeMassProperties(d + "hanger.off").centre_of_mass.z(), -54.4, 0.1);
  EXPECT_NEAR(ComputeMassProperties(d + "turnbuckle.stl").volume_mm3, 2005, 5);
  EXPECT_THROW(ComputeMassProperties(d + "no_such_mesh.obj"), fabatlas::InputError);
}

TEST(AssemblyProgram, ParseErrorsNameFileLineColumn) {
  const std::string lib = Source() + "/configs/assemblies/parts.yaml";
  const std::string mesh = Shared() + "/data/fabhacks/meshes";
  try {
    ParseProgram(
        "start_with: {name: door, part: DoorRod, frame: [[0,0,0],[0,0,0]]}\n"
        "end_with: {name: b, part: SoapBottle, frame: [[0,0,0],[0,0,0]]}\n"
        "steps:\n  - {attach: b.surface, to: door.pole}\n",
        "prog.yaml", lib, mesh);
    FAIL() << "expected InputError";
  } catch (const fabatlas::InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("prog.yaml:4:", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find("no primitive 'pole'"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
  }
  // attach onto a part that is not placed yet.
  EXPECT_THROW(ParseProgram("start_with: {name: door, part: DoorRod, frame: [[0,0,0],[0,0,0]]}\n"
                            "parts: {e: HookEyeLeftS}\n"
                            "end_with: {name: b, part: Basket, frame: [[0,0,0],[0,0,0]]}\n"
                            "steps:\n  - {attach: b.rod1, to: e.hook}\n  - {attach: e.ring, to: door.door}\n",
                            "order.yaml", lib, mesh),
               fabatlas::InputError);
  EXPECT_THROW(ParseProgram("start_with: [", "bad.yaml", lib, mesh), fabatlas::InputError);
  EXPECT_THROW(ParseProgram("start_with: {name: d, part: Nope, frame: [0,0,0,0,0,0]}\n", "p.yaml", lib, mesh),
               fabatlas::InputError);
}

TEST(AssemblyProgram, ConnectionSemanticsOfTheReference) {
  // Soap bottle holder (PARTS.md §4 ex 3): attach keys use variant names with
  // the placed primitive first, connect keys base names; the basket surface
  // gets the reduced range 77/496 .. 1 − 77/496 and the bottle's surface its
  // fixed base form; the two eyehook rings share the door rod, so their
  // starting t are spread to 1/3 and 2/3.
  const Program p =
      LoadProgram(Source() + "/configs/assemblies/soap_bottle_holder.yaml", Shared() + "/data/fabhacks/meshes");
  ASSERT_EQ(p.connections.size(), 5u);
  EXPECT_EQ(p.connections[0].key, "Rod_RingFlex");
  EXPECT_FALSE(p.connections[0].closing);
  EXPECT_EQ(p.connections[1].key, "Hook_Rod");
  EXPECT_EQ(p.connections[3].key, "Hook_Rod");
  EXPECT_TRUE(p.connections[3].closing);
  EXPECT_TRUE(p.connections[2].align.isApprox(EulerToRotation({180, 0, -90}), 1e-12));
  const Connection& s = p.connections[4];
  EXPECT_EQ(s.key, "Surface_Surface");
  EXPECT_NEAR(s.params_a[0].min, 77.0 / 496, 1e-12);
  EXPECT_NEAR(s.params_a[0].max, 1 - 77.0 / 496, 1e-12);
  EXPECT_TRUE(s.params_b[0].held && s.params_b[1].held && s.params_b[2].held);
  EXPECT_NEAR(p.connections[0].params_a[0].init, 1.0 / 3, 1e-12);
  EXPECT_NEAR(p.connections[2].params_a[0].init, 2.0 / 3, 1e-12);
}
