#include "fabatlas/fem/hex_mesh.h"

#include <gtest/gtest.h>

#include "fabatlas/error.h"

namespace fabatlas::fem {
namespace {

VoxelSolid Grid(int nx, int ny, int nz, double h) {
  VoxelSolid s;
  s.voxel_size = h;
  s.dims = {nx, ny, nz};
  s.occupied.assign(static_cast<std::size_t>(nx) * ny * nz, 1);
  return s;
}

TEST(FemHexMeshFromVoxels, NeighbouringVoxelsShareNodes) {
  VoxelSolid s = Grid(2, 1, 1, 0.5);
  s.origin = {10, 20, 30};
  const HexMesh m = HexMeshFromVoxels(s);
  ASSERT_EQ(m.elements.size(), 2u);
  EXPECT_EQ(m.nodes.size(), 12u);  // 3 x 2 x 2 lattice points
  int shared = 0;
  for (int a : m.elements[0])
    for (int b : m.elements[1]) shared += (a == b);
  EXPECT_EQ(shared, 4);
  // Standard Q1 order: node 0 is the min corner, node 6 the max corner.
  const Vec3 lo = m.nodes[m.elements[0][0]], hi = m.nodes[m.elements[0][6]];
  EXPECT_DOUBLE_EQ(lo[0], 10.0);
  EXPECT_DOUBLE_EQ(lo[2], 30.0);
  EXPECT_DOUBLE_EQ(hi[0], 10.5);
  EXPECT_DOUBLE_EQ(hi[1], 20.5);
  EXPECT_DOUBLE_EQ(m.nodes[m.elements[0][1]][0], 10.5);  // node 1: +x
  EXPECT_DOUBLE_EQ(m.nodes[m.elements[0][3]][1], 20.5);  // node 3: +y
  EXPECT_DOUBLE_EQ(m.nodes[m.elements[0][4]][2], 30.5);  // node 4: +z
  EXPECT_EQ(BoundaryFaces(m).size(), 10u);
}

TEST(FemHexMeshFromVoxels, OnlyOccupiedVoxelsAndTheirCorners) {
  VoxelSolid s = Grid(3, 3, 3, 1.0);
  std::fill(s.occupied.begin(), s.occupied.end(), 0);
  s.occupied[s.Index(0, 0, 0)] = 1;
  s.occupied[s.Index(2, 2, 2)] = 1;  // touches nothing
  const HexMesh m = HexMeshFromVoxels(s);
  EXPECT_EQ(m.elements.size(), 2u);
  EXPECT_EQ(m.nodes.size(), 16u);
  EXPECT_EQ(BoundaryFaces(m).size(), 12u);
  // A full 3^3 block: 4^3 nodes, 6 * 9 boundary faces.
  const HexMesh full = HexMeshFromVoxels(Grid(3, 3, 3, 1.0));
  EXPECT_EQ(full.nodes.size(), 64u);
  EXPECT_EQ(BoundaryFaces(full).size(), 54u);
}

TEST(FemHexMeshFromVoxels, RejectsBadInput) {
  VoxelSolid s = Grid(2, 2, 2, 1.0);
  s.occupied.pop_back();
  EXPECT_THROW(HexMeshFromVoxels(s), InputError);
  VoxelSolid t = Grid(2, 2, 2, 0.0);
  EXPECT_THROW(HexMeshFromVoxels(t), InputError);
}

TEST(FemHexMeshFromQuadPatch, StructuredTrapezoid) {
  const HexMesh m = HexMeshFromQuadPatch({Vec2{0, 0}, Vec2{48, 44}, Vec2{48, 60}, Vec2{0, 44}}, 4, 4, 1.0);
  EXPECT_EQ(m.elements.size(), 16u);
  EXPECT_EQ(m.nodes.size(), 50u);
  // Node (i=4, j=2, k=0) is the midpoint of the right edge, (48, 52).
  const Vec3 p = m.nodes[4 + 5 * 2];
  EXPECT_DOUBLE_EQ(p[0], 48.0);
  EXPECT_DOUBLE_EQ(p[1], 52.0);
}

}  // namespace
}  // namespace fabatlas::fem
