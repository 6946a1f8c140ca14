// The nested-dissection order of voxel meshes (George 1973): a permutation
// of the nodes whose last nodes are the middle node layer of a cube, George's
// first separator, with the two halves before it.
#include "fabatlas/fem/nested_dissection.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace fabatlas::fem {
namespace {

HexMesh Cube(int n) {
  VoxelSolid v;
  v.dims = {n, n, n};
  v.occupied.assign(static_cast<std::size_t>(n) * n * n, 1);
  return HexMeshFromVoxels(v);
}

TEST(FemNestedDissection, CubeIsCutAtItsMiddleLayerFirst) {
  const HexMesh mesh = Cube(6);  // 7 x 7 x 7 nodes
  const std::vector<int> order = NestedDissectionOrder(mesh);
  ASSERT_EQ(order.size(), mesh.nodes.size());
  std::vector<int> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], static_cast<int>(i));
  // The last 49 nodes: the layer x = 3 (all three axes tie; x first).
  for (std::size_t i = order.size() - 49; i < order.size(); ++i) EXPECT_EQ(mesh.nodes[order[i]][0], 3.0) << i;
  // Before it, the three layers x < 3 (147 nodes), then those x > 3.
  for (std::size_t i = 0; i < 147; ++i) EXPECT_LT(mesh.nodes[order[i]][0], 3.0) << i;
  for (std::size_t i = 147; i < order.size() - 49; ++i) EXPECT_GT(mesh.nodes[order[i]][0], 3.0) << i;
}

}  // namespace
}  // namespace fabatlas::fem
