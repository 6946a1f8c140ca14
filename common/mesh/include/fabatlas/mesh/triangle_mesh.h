// fabatlas/mesh/triangle_mesh.h — the plain triangle mesh exchanged between
// libraries. Units are millimetres; triangles are counter-clockwise seen from
// outside (outward normals) when the mesh is a closed solid. No geometry
// library's types appear here, so any header may include it.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "fabatlas/vec3.h"

namespace fabatlas::mesh {

struct TriangleMesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<std::int32_t, 3>> triangles;

  bool empty() const { return triangles.empty(); }
};

}  // namespace fabatlas::mesh
