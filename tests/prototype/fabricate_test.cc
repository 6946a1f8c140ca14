// Printable geometry of the Koo et al. examples: watertight, manifold, free
// of self-intersections, and free of interference: exactly one piece per part
// plus one per double-pivot link (no two parts fused across a print gap, no
// part, yoke or rail tongue cut loose from its part). The self-intersection
// test (CGAL, 10-26 s on these meshes of 0.7-1.2 M triangles) runs here on
// the first three examples only; `fabatlas prototype --stl` reports it for
// all nine (docs/prototype.md).
#include <gtest/gtest.h>

#include "fabatlas/error.h"
#include "fabatlas/mesh/mesh_report.h"
#include "fabatlas/prototype/fabricate.h"
#include "fabatlas/swept/carve.h"
#include "fabatlas/testing/paths.h"

namespace fabatlas::prototype {
namespace {

void ExpectPrintable(const std::string& name, bool check_self_intersection) {
  Prototype p = LoadPrototype(testing::SourceDir() / "configs" / "prototypes" / (name + ".yaml"));
  SolveSummary s = SolvePrototype(p);
  ASSERT_TRUE(s.satisfiable) << s.Explain();
  geometry::GridSpec g;
  g.voxel_size = p.fabrication.gap / 2;  // the gap spans two voxels
  FabricateSummary fs;
  geometry::Solid solid = Fabricate(p, s, g, &fs);
  mesh::TriangleMesh m = solid.ToMesh();
  mesh::InspectOptions options;
  options.check_self_intersection = check_self_intersection;
  mesh::MeshReport r = mesh::InspectMesh(m, options);
  EXPECT_TRUE(r.closed) << r.Reasons();
  EXPECT_TRUE(r.manifold) << r.Reasons();
  EXPECT_FALSE(r.self_intersecting) << r.Reasons();
  EXPECT_TRUE(r.outward) << r.Reasons();
  int links = 0;
  for (const Joint& j : p.joints) links += j.type == JointType::kDoublePivot;
  EXPECT_EQ(r.components, static_cast<int>(p.parts.size()) + links) << name;
  bool joint_geometry = false;  // slides without rails run in cavities: no pieces
  for (const Joint& j : p.joints) joint_geometry |= j.type != JointType::kSlide || !j.on.empty();
  EXPECT_EQ(fs.joint_pieces > 0, joint_geometry) << name;
  for (const auto& [part, v] : fs.part_volumes) EXPECT_GT(v, 0) << part;
}

TEST(PrototypeFabricate, CabinetIsPrintable) { ExpectPrintable("cabinet", true); }
TEST(PrototypeFabricate, CrateBarIsPrintable) { ExpectPrintable("crate_bar", false); }
TEST(PrototypeFabricate, CrateBedIsPrintable) { ExpectPrintable("crate_bed", true); }
TEST(PrototypeFabricate, SofaBunkIsPrintable) { ExpectPrintable("sofa_bunk", true); }
TEST(PrototypeFabricate, PrinterIsPrintable) { ExpectPrintable("printer", false); }
TEST(PrototypeFabricate, CellphoneIsPrintable) { ExpectPrintable("cellphone", false); }
TEST(PrototypeFabricate, TabletIsPrintable) { ExpectPrintable("tablet", false); }
TEST(PrototypeFabricate, ToolboxIsPrintable) { ExpectPrintable("toolbox", false); }
TEST(PrototypeFabricate, JewelleryBoxIsPrintable) { ExpectPrintable("jewellery_box", false); }

// Mated rails (Koo et al. Sec. 7): the tablet's printed stand runs along its
// slide over the whole travel (0 to -25 mm, every 2.5 mm) without
// touching the printed left half, and it is held: lifted off the rail face
// (0.5 to 3 mm, the tongue reaching 3 mm into the left half) its flange
// hits the slot's lip once past the 1 mm print gap, where a stand without
// rails would come free.
TEST(PrototypeFabricate, RailsRunFreelyAndHoldTheStand) {
  Prototype p = LoadPrototype(testing::SourceDir() / "configs" / "prototypes" / "tablet.yaml");
  SolveSummary s = SolvePrototype(p);
  ASSERT_TRUE(s.satisfiable) << s.Explain();
  geometry::GridSpec g;
  g.voxel_size = p.fabrication.gap / 2;
  mesh::TriangleMesh left, stand;
  for (const FabricatedPiece& piece : FabricatePieces(p, s, g)) {
    if (piece.name == "left") left = piece.solid.ToMesh();
    if (piece.name == "stand") stand = piece.solid.ToMesh();
  }
  ASSERT_FALSE(left.empty());
  ASSERT_FALSE(stand.empty());
  auto shifted = [](int axis, double d) {
    swept::Transform t;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) t.rotation[a][b] = a == b;
    t.translation = {0, 0, 0};
    t.translation[axis] = d;
    return t;
  };
  std::vector<swept::Transform> travel;
  for (int k = 0; k <= 10; ++k) travel.push_back(shifted(2, -2.5 * k));
  EXPECT_FALSE(swept::CollidesAtAnyPose(left, stand, travel));
  std::vector<swept::Transform> lift;
  for (int k = 1; k <= 6; ++k) lift.push_back(shifted(1, 0.5 * k));
  EXPECT_TRUE(swept::CollidesAtAnyPose(left, stand, lift));
}

// Rails need material under the rail face: a 3 mm bed cannot take a slot
// 2u + 2 gap = 3 mm deep plus a 2-voxel floor, 3.5 mm (u = 2 voxels = 0.5 mm,
// gap 1 mm). One line naming the file place, the joint and both depths.
TEST(PrototypeFabricate, TooThinForRailsIsNamed) {
  Prototype p = ParsePrototype(R"(
fabrication: {voxel: 0.25, gap: 1.0}
parts:
  bed:      {box: [0, 40, 0, 20, 0, 3], hold: [x0, x1, y0, y1, z0, z1]}
  carriage: {box: [0, 10, 0, 20, 3, 8]}
joints:
  s: {type: slide, child: carriage, parent: bed, axis: x, on: [carriage.z0, bed.z1]}
)",
                               "thin.yaml");
  SolveSummary s = SolvePrototype(p);
  ASSERT_TRUE(s.satisfiable) << s.Explain();
  geometry::GridSpec g;
  g.voxel_size = 0.25;
  try {
    FabricatePieces(p, s, g);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("thin.yaml:7:", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find("slide s: bed is 3.00 mm deep under its rail face; rails need 3.50"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace fabatlas::prototype
