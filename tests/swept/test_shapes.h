// Closed triangle meshes for the swept-volume tests and benchmark.
#pragma once

#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <utility>

#include "../mesh/synthetic_meshes.h"
#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::swept::testing {

// Icosphere of the given radius (vertices on the sphere), outward: the mesh
// tests' IcoSphere.
using mesh::testing::IcoSphere;

// Axis-aligned box [lo, hi], 12 triangles, outward.
inline mesh::TriangleMesh BoxMesh(const std::array<double, 3>& lo, const std::array<double, 3>& hi) {
  mesh::TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.push_back({(i & 1) ? hi[0] : lo[0], (i & 2) ? hi[1] : lo[1], (i & 4) ? hi[2] : lo[2]});
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

// Torus in the xy-plane with nu x nv quads (2 nu nv triangles), outward.
inline mesh::TriangleMesh Torus(double major, double minor, int nu, int nv) {
  mesh::TriangleMesh m;
  for (int i = 0; i < nu; ++i) {
    const double u = 2 * std::numbers::pi * i / nu;
    for (int j = 0; j < nv; ++j) {
      const double v = 2 * std::numbers::pi * j / nv;
      const double r = major + minor * std::cos(v);
      m.vertices.push_back({r * std::cos(u), r * std::sin(u), minor * std::sin(v)});
    }
  }
  auto id = [&](int i, int j) { return ((i + nu) % nu) * nv + (j + nv) % nv; };
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  return m;
}

}  // namespace fabatlas::swept::testing
