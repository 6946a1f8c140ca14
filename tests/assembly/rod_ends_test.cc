// Rod ends against the part meshes (rod_ends.h): which end of a rod a
// connector can slide off is read from the mesh, not from the data's flags.
// The reading nook's peg rod2 (readingroom.stl, a PolyCam scan) is pinned to
// the scan: t = 0 is its room side, t = 1 its wall side, and the scanned body
// continues past both ends, so both are blocked in parts.yaml; the charger's
// cable is the control: its blocked upper end runs into the plug, its lower
// end is free.
#include <string>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "fabatlas/testing/paths.h"

#include "fabatlas/assembly/fit_primitive.h"
#include "fabatlas/assembly/mass_properties.h"
#include "fabatlas/assembly/part_library.h"
#include "fabatlas/assembly/program.h"
#include "fabatlas/assembly/rod_ends.h"

using namespace fabatlas::assembly;

namespace {

PartLibrary Library() {
  return LoadPartLibrary((fabatlas::testing::SourceDir() / "configs/assemblies/parts.yaml").string(), DefaultMeshDir());
}

PartMesh Mesh(const Part& part) { return ReadPartMesh(DefaultMeshDir() + "/" + part.mesh); }

}  // namespace

TEST(AssemblyRodEnds, ReadingNookPegIsClosedAtBothEndsByTheScan) {
  const PartLibrary lib = Library();
  const Part& room = lib.parts.at("ReadingRoom");
  const Primitive& rod2 = *room.Find("rod2");
  const PartMesh mesh = Mesh(room);
  const RodEnds e = MeasureRodEnds(mesh, rod2);

  // PARTS.md §1.1 / §3: frame [72.2,-1375,1293.7]/[120,0,0], L 20: the axis
  // z_B = Rx(120)·z = (0, -0.866, -0.5); t = 0 is the end 30° up into the room.
  EXPECT_LT((e.t0.position - Eigen::Vector3d(72.2, -1366.340, 1298.7)).norm(), 0.01);
  EXPECT_LT((e.t1.position - Eigen::Vector3d(72.2, -1383.660, 1288.7)).norm(), 0.01);
  EXPECT_LT((e.t0.outward - Eigen::Vector3d(0, std::sqrt(3.0) / 2, 0.5)).norm(), 1e-9);

  // The wall under the peg (the scan's vertices 100-300 mm below it, a plane
  // to 1 mm) faces the room (+y); t = 1 is the end next to it.
  const auto wall = MeshPointsIn(DefaultMeshDir() + "/" + room.mesh, Eigen::Vector3d(0, -1500, 1000),
                                 Eigen::Vector3d(150, -1300, 1250));
  ASSERT_GT(wall.size(), 30u);
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const auto& p : wall) centre += p;
  centre /= wall.size();
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : wall) cov += (p - centre) * (p - centre).transpose();
  Eigen::Vector3d normal = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0);
  if (normal.y() < 0) normal = -normal;
  EXPECT_GT(normal.y(), 0.99);
  const double front0 = (e.t0.position - centre).dot(normal), front1 = (e.t1.position - centre).dot(normal);
  EXPECT_GT(front0, 20);  // 22.8 mm in front of the wall
  EXPECT_GT(front1, 0);   //  5.7 mm
  EXPECT_LT(front1, 10);

  // Past t = 0 the axis runs into the scanned body above the peg: 20 and 40
  // mm past the end it is inside it, deeper than the turnbuckle hook hanging
  // there reaches from the axis (arc radius + wire radius), so the hook cannot
  // slide off that end. Past t = 1 it is behind the wall.
  const Primitive& hook = *lib.parts.at("Turnbuckle40").Find("hook1");
  const double reach = hook.Shape("arc_radius") + hook.Shape("thickness");
  for (const RodEndProbe& q : e.t0.probes) {
    EXPECT_TRUE(q.Enclosed()) << q.past_mm << " mm past t = 0: " << q.hits_from_inside << "/" << q.rays_hit;
    if (q.past_mm >= 20) {
      EXPECT_GT(q.distance_mm, reach) << q.past_mm;
    }
  }
  for (const RodEndProbe& q : e.t1.probes)
    EXPECT_TRUE(q.Enclosed()) << q.past_mm << " mm past t = 1: " << q.hits_from_inside << "/" << q.rays_hit;
  EXPECT_TRUE(rod2.blocked_min);
  EXPECT_TRUE(rod2.blocked_max);
}

TEST(AssemblyRodEnds, CableIsBlockedAtThePlugAndFreeBelow) {
  const PartLibrary lib = Library();
  const Part& cable = lib.parts.at("Cable");
  const Primitive& rod1 = *cable.Find("rod1");
  const RodEnds e = MeasureRodEnds(Mesh(cable), rod1);
  ASSERT_TRUE(rod1.blocked_max);
  ASSERT_FALSE(rod1.blocked_min);
  for (const RodEndProbe& q : e.t1.probes)
    if (q.past_mm <= 20) {
      EXPECT_TRUE(q.Enclosed()) << q.past_mm << " mm past the plug end";
    }
  for (const RodEndProbe& q : e.t0.probes) EXPECT_FALSE(q.Enclosed()) << q.past_mm << " mm past the free end";
}

TEST(AssemblyRodEnds, EveryBlockedRodEndRunsIntoItsMesh) {
  const PartLibrary lib = Library();
  int blocked = 0;
  for (const auto& [name, part] : lib.parts) {
    if (part.mesh.empty()) continue;
    for (const Primitive& p : part.primitives) {
      if (p.type != PrimitiveType::kRod || (!p.blocked_min && !p.blocked_max)) continue;
      const RodEnds e = MeasureRodEnds(Mesh(part), p);
      for (const RodEnd* end : {p.blocked_min ? &e.t0 : nullptr, p.blocked_max ? &e.t1 : nullptr}) {
        if (!end) continue;
        ++blocked;
        EXPECT_TRUE(end->probes[0].Enclosed() && end->probes[1].Enclosed()) << name << "." << p.name;
      }
    }
  }
  EXPECT_EQ(blocked, 3);  // Cable.rod1 t = 1, ReadingRoom.rod2 both
}
