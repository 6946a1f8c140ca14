// Printable geometry of the three Koo et al. examples: watertight, manifold,
// free of self-intersections, and in separate pieces (print gaps).
#include <gtest/gtest.h>

#include "fabatlas/mesh/mesh_report.h"
#include "fabatlas/prototype/fabricate.h"
#include "fabatlas/testing/paths.h"

namespace fabatlas::prototype {
namespace {

void ExpectPrintable(const std::string& name, int min_pieces) {
  Prototype p = LoadPrototype(testing::SourceDir() / "configs" / "prototypes" / (name + ".yaml"));
  SolveSummary s = SolvePrototype(p);
  ASSERT_TRUE(s.satisfiable) << s.Explain();
  geometry::GridSpec g;
  g.voxel_size = p.fabrication.gap / 2;  // the gap spans two voxels
  FabricateSummary fs;
  geometry::Solid solid = Fabricate(p, s, g, &fs);
  mesh::TriangleMesh m = solid.ToMesh();
  mesh::MeshReport r = mesh::InspectMesh(m);
  EXPECT_TRUE(r.closed) << r.Reasons();
  EXPECT_TRUE(r.manifold) << r.Reasons();
  EXPECT_FALSE(r.self_intersecting) << r.Reasons();
  EXPECT_TRUE(r.outward) << r.Reasons();
  EXPECT_GE(r.components, min_pieces) << name;
  EXPECT_GT(fs.joint_pieces, 0);
  for (const auto& [part, v] : fs.part_volumes) EXPECT_GT(v, 0) << part;
}

TEST(PrototypeFabricate, CabinetIsPrintable) { ExpectPrintable("cabinet", 6); }
TEST(PrototypeFabricate, CrateBedIsPrintable) { ExpectPrintable("crate_bed", 7); }
TEST(PrototypeFabricate, SofaBunkIsPrintable) { ExpectPrintable("sofa_bunk", 7); }

}  // namespace
}  // namespace fabatlas::prototype
