// What the watertight check's guarantee on a sample's own surface rests on
// (docs/mesh.md, "Which check runs where"): the level-set extraction
// (Solid::ToMesh) is closed and manifold for any pattern of signs, so the
// per-sample test looks only for what it can get wrong, folds
// (FindFoldedTriangles), which appear where a part is thinner than about a
// voxel and wherever CGAL finds the extraction intersecting itself.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>

#include <tbb/task_arena.h>

#include "fabatlas/geometry/folded_triangles.h"
#include "fabatlas/geometry/solid.h"
#include "fabatlas/mesh/mesh_report.h"
#include "fabatlas/testing/paths.h"
#include "js_mesh.h"

namespace fabatlas::geometry {
namespace {

GridSpec Grid(double voxel) {
  GridSpec g;
  g.voxel_size = voxel;
  g.half_width_voxels = 3;
  return g;
}

// Random inside/outside per voxel (a 12-voxel cube of noise, each voxel
// inside with probability p): the hardest sign patterns there are; every one
// extracts to a closed 2-manifold (the full InspectMesh, with its merge of
// coincident vertices).
TEST(LevelSetExtraction, IsClosedAndManifoldForAnySigns) {
  const GridSpec g = Grid(0.5);
  std::mt19937 rng(14);
  for (int i = 0; i < 20; ++i) {
    const double p = 0.2 + 0.03 * i;
    const std::uint32_t seed = rng();
    const Solid s = FromDistance(
        g, {{-3, -3, -3}, {3, 3, 3}},
        [&](double x, double y, double z) {
          const double box = std::max({std::abs(x), std::abs(y), std::abs(z)}) - 2.5;
          std::uint32_t h = seed ^ static_cast<std::uint32_t>(std::lround(x / 0.5) * 73856093) ^
                            static_cast<std::uint32_t>(std::lround(y / 0.5) * 19349663) ^
                            static_cast<std::uint32_t>(std::lround(z / 0.5) * 83492791);
          h = (h ^ (h >> 13)) * 0x5bd1e995u;
          h ^= h >> 15;
          return std::max(box, (h % 1000) < p * 1000 ? -0.25 : 0.25);
        },
        "noise");
    const mesh::TriangleMesh m = s.ToMesh();
    ASSERT_GT(m.triangles.size(), 0u) << "p " << p;
    mesh::InspectOptions topology;
    topology.check_self_intersection = false;
    const mesh::MeshReport r = mesh::InspectMesh(m, topology);
    EXPECT_TRUE(r.closed) << "p " << p << ": " << r.closed_reason;
    EXPECT_TRUE(r.manifold) << "p " << p << ": " << r.manifold_reason;
  }
}

// The npm teapot (open, unstitched patches, docs/mesh.md) flood-filled into a
// solid: CGAL finds our extraction of its thin parts intersecting itself at
// voxels 0.05 and 0.1 mm, and the fold test fails there too; the npm bunny
// (a clean closed surface) extracts with neither.
TEST(FoldedTriangles, WhereCgalFindsTheExtractionSelfIntersecting) {
  const mesh::TriangleMesh teapot = mesh::testing::LoadJsMesh(testing::SourceDir() / "node_modules/teapot/teapot.js");
  const mesh::TriangleMesh bunny = mesh::testing::LoadJsMesh(testing::SourceDir() / "node_modules/bunny/index.js");
  for (double voxel : {0.05, 0.1}) {
    const Solid t = FromMesh(Grid(voxel), teapot);
    const mesh::TriangleMesh tm = t.ToMesh();
    const mesh::MeshReport tr = mesh::InspectMesh(tm);
    EXPECT_TRUE(tr.self_intersecting) << voxel;
    EXPECT_GT(FindFoldedTriangles(t, tm).area, voxel * voxel) << voxel;  // what the watertight check fails on

    const Solid b = FromMesh(Grid(voxel), bunny);
    const mesh::TriangleMesh bm = b.ToMesh();
    const mesh::MeshReport br = mesh::InspectMesh(bm);
    EXPECT_FALSE(br.self_intersecting) << voxel << ": " << br.self_intersection_reason;
    EXPECT_EQ(FindFoldedTriangles(b, bm).count, 0) << voxel;
  }
}

// A tilted wall standing on a base (boxes centred at the origin) at voxel 0.5 mm: 0.3 mm thick it folds (its two
// faces' vertices share cells), 1 mm thick it does not; neither is open,
// non-manifold or (by CGAL) self-intersecting, so only the fold test sees
// the unresolved wall.
TEST(FoldedTriangles, AWallThinnerThanAVoxelFolds) {
  const GridSpec g = Grid(0.5);
  auto wall_on_base = [&](double t) {
    return Union(Box(g, {10, 10, 1}), Translate(Rotate(Box(g, {t, 8, 6}), {0, 30, 10}), {1, 0, 3}));
  };
  const Solid thin = wall_on_base(0.3), thick = wall_on_base(1.0);
  const mesh::TriangleMesh thin_mesh = thin.ToMesh(), thick_mesh = thick.ToMesh();
  const mesh::MeshReport r = mesh::InspectMesh(thin_mesh);
  EXPECT_TRUE(r.closed && r.manifold && !r.self_intersecting) << r.Reasons();
  const FoldedTriangles folds = FindFoldedTriangles(thin, thin_mesh);
  EXPECT_GT(folds.area, 0.5 * 0.5);  // more than a voxel face: what the watertight check fails on
  EXPECT_GT(folds.first[2], 0.5);    // on the wall (z 0.3-5.7), above the base (z -0.5-0.5)
  EXPECT_EQ(FindFoldedTriangles(thick, thick_mesh).count, 0);
}

// The fold test runs over ranges of triangles in parallel: on one thread
// and on every thread it finds the same folds, the same area to the bit and
// the same first one (the teapot's extraction at 0.1 mm: 21 folds).
TEST(FoldedTriangles, TheSameForAnyThreadCount) {
  const mesh::TriangleMesh teapot = mesh::testing::LoadJsMesh(testing::SourceDir() / "node_modules/teapot/teapot.js");
  const Solid t = FromMesh(Grid(0.1), teapot);
  const mesh::TriangleMesh tm = t.ToMesh();
  FoldedTriangles one;
  tbb::task_arena(1).execute([&] { one = FindFoldedTriangles(t, tm); });
  const FoldedTriangles all = FindFoldedTriangles(t, tm);
  EXPECT_GT(one.count, 0);
  EXPECT_EQ(all.count, one.count);
  EXPECT_EQ(all.area, one.area);
  EXPECT_EQ(all.first, one.first);
}

}  // namespace
}  // namespace fabatlas::geometry
