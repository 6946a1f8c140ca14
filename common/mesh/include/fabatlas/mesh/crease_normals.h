// fabatlas/mesh/crease_normals.h — vertex normals for flat shading at creases
// and smooth shading elsewhere, for previews of exact meshes (the mesh road's
// boxes and cylinders): a vertex shared by faces that meet at a sharp edge
// gets one copy per side of the crease.
#pragma once

#include <array>
#include <vector>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::mesh {

struct CreasedMesh {
  TriangleMesh mesh;                          // the same triangles; vertices split at creases
  std::vector<std::array<float, 3>> normals;  // unit normal per vertex of `mesh`
};

// Around each vertex, faces are grouped greedily in triangle order: a face
// joins the first group whose first face's normal is within crease_degrees of
// its own, else starts a group. Each group is a vertex of the result whose
// normal is the area-weighted mean of the group's face normals. Degenerate
// faces (no area) join the first group. Deterministic; single-threaded,
// O(sum over vertices of faces^2 / groups).
CreasedMesh CreaseNormals(const TriangleMesh& m, double crease_degrees = 30.0);

}  // namespace fabatlas::mesh
