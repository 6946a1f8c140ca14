// fabatlas/geometry/convex_mesh_distance.h — the signed distance of a closed
// convex triangle mesh, as geometry::FromMesh samples it.
#pragma once

#include <algorithm>
#include <cmath>

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
// The function is thread-safe (it only reads its copy of the faces). For an
// axis-aligned box (six faces with normals along the axes: every OpenSCAD
// cube under a translation or scale) it holds a BoxDistance, which a caller
// evaluating many points may call directly (`target<BoxDistance>()`) instead
// of through the std::function: the same arithmetic.
DistanceFunction ConvexMeshDistance(const mesh::TriangleMesh& m, double exact_within);

// The signed distance of the box [lo, hi] (mm, negative inside) in closed
// form, exact everywhere.
struct BoxDistance {
  Vec3 lo, hi;
  double operator()(double x, double y, double z) const {
    const double qx = std::max(lo[0] - x, x - hi[0]), qy = std::max(lo[1] - y, y - hi[1]),
                 qz = std::max(lo[2] - z, z - hi[2]);
    const double ox = std::max(qx, 0.0), oy = std::max(qy, 0.0), oz = std::max(qz, 0.0);
    return std::sqrt(ox * ox + oy * oy + oz * oz) + std::min(std::max({qx, qy, qz}), 0.0);
  }
};

}  // namespace fabatlas::geometry
