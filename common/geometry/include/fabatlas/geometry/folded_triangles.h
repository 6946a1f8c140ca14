// fabatlas/geometry/folded_triangles.h — where a solid's extracted surface
// folds over itself: triangles of Solid::ToMesh facing against the level
// set's outward direction.
//
// OpenVDB's volumeToMesh is closed and manifold by construction (a vertex
// per edge group of each cell, so any pattern of signs gives a closed
// 2-manifold; tests/geometry/folded_triangles_test.cc checks it on random
// sign patterns). What it can get wrong is geometry: where material is
// thinner than about a voxel, the two sides' vertices fall into the same
// cells and the surface folds, a patch facing inward, and can intersect
// itself (the full CGAL test finds intersecting pairs there). A folded
// triangle here is one whose normal points against the level set's
// gradient at its centroid (the solid's outward direction there) and whose
// material ends within a voxel: one voxel inward along the gradient the
// level set is outside again. Inward-facing triangles in a crease where two
// parts meet (material continues behind them) are not counted. The
// watertight check fails when the folds cover more than one voxel face.
#pragma once

#include <cstdint>

#include "fabatlas/geometry/solid.h"
#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::geometry {

struct FoldedTriangles {
  std::int64_t count = 0;  // folded triangles
  double area = 0;         // their total area, mm^2
  Vec3 first{0, 0, 0};     // centroid (mm) of the first one, in mesh order
};

// `mesh` is s.ToMesh(). The gradient is that of the trilinear interpolant
// of the eight voxel values around each triangle's centroid; an inward
// facing triangle costs one more trilinear sample. Degenerate triangles and
// centroids where the gradient vanishes are not counted. Parallel over
// ranges of triangles (TBB); count, area and first are summed in mesh order
// afterwards, so the result is the same bits for any thread count. About
// 4 ms of CPU for the tray's 83k triangles (perf, load 3-9).
FoldedTriangles FindFoldedTriangles(const Solid& s, const mesh::TriangleMesh& mesh);

}  // namespace fabatlas::geometry
