// Every triangle of a mesh with its vertices taken about an origin (internal
// to fabatlas_mesh): the loop of the divergence-theorem measures
// (enclosed_volume.cc, surface_area.cc).
#pragma once

#include <array>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::mesh {

// Calls visit(p) for each triangle in order, p[k] = vertex k - origin.
template <class Visit>
void ForEachTriangleAbout(const TriangleMesh& mesh, const std::array<double, 3>& origin, Visit&& visit) {
  for (const auto& t : mesh.triangles) {
    std::array<std::array<double, 3>, 3> p;
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) p[k][a] = mesh.vertices[t[k]][a] - origin[a];
    visit(p);
  }
}

}  // namespace fabatlas::mesh
