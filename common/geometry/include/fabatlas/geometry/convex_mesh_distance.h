// fabatlas/geometry/convex_mesh_distance.h — the signed distance of a closed
// convex triangle mesh, as geometry::FromMesh samples it.
#pragma once

#include "fabatlas/geometry/solid.h"
#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::geometry {

// The signed distance of a closed convex triangle mesh `m` (mm, negative
// inside): exact within `exact_within` mm of its surface (inside: the largest
// face-plane value; outside: the nearest triangle of the faces in front of the
// point), beyond it the largest face-plane value, a lower bound in magnitude,
// as FromDistance requires. Empty when `m` is not closed and convex (every
// edge shared by two triangles, every vertex behind every face plane within
// 1e-9 of its size), has a bad index, or has more than 20,000 triangles.
// The function is thread-safe (it only reads its copy of the faces).
DistanceFunction ConvexMeshDistance(const mesh::TriangleMesh& m, double exact_within);

}  // namespace fabatlas::geometry
