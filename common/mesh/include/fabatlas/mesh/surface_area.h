// fabatlas/mesh/surface_area.h — the area of a triangle mesh's surface: the
// sum over its triangles (a, b, c) of |(b - a) x (c - a)| / 2.
#pragma once

#include <array>

#include "fabatlas/mesh/triangle_mesh.h"
#include "fabatlas/vec3.h"

namespace fabatlas::mesh {

// Input: a triangle mesh in millimetres; `origin` o, subtracted from every
// vertex first (the area does not depend on it; near the mesh, e.g. its
// bounding-box centre, it keeps rounding small for a mesh far from
// (0, 0, 0)). Output: the area in mm^2. Deterministic: triangles summed in
// order.
double SurfaceArea(const TriangleMesh& mesh, const Vec3& origin = {0.0, 0.0, 0.0});

}  // namespace fabatlas::mesh
