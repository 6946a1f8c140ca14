// fabatlas/mesh/enclosed_volume.h — the signed volume a closed triangle mesh
// encloses, by the divergence theorem: the sum over its triangles (a, b, c)
// of det[a - o, b - o, c - o] / 6 for an origin o.
#pragma once

#include <array>

#include "fabatlas/mesh/triangle_mesh.h"
#include "fabatlas/vec3.h"

namespace fabatlas::mesh {

// Input: a closed triangle mesh in millimetres; `origin` o, which does not
// change the value for a closed mesh but, near the mesh (e.g. its bounding
// box centre), keeps rounding small for a mesh far from (0, 0, 0).
// Output: the enclosed volume in mm^3, positive when the triangles are
// counter-clockwise seen from outside (outward normals), negative when they
// are all reversed; for an open mesh, the signed volume of the cone the
// surface spans from o. Deterministic: triangles summed in order.
double EnclosedVolume(const TriangleMesh& mesh, const Vec3& origin = {0.0, 0.0, 0.0});

}  // namespace fabatlas::mesh
