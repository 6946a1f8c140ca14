// Closed triangle meshes for the swept-volume tests and benchmark.
#pragma once

#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <utility>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::swept::testing {

// Icosphere of the given radius (vertices on the sphere), outward.
inline mesh::TriangleMesh Icosphere(double radius, int subdivisions) {
  mesh::TriangleMesh m;
  const double p = (1 + std::sqrt(5.0)) / 2;
  m.vertices = {{-1, p, 0}, {1, p, 0}, {-1, -p, 0}, {1, -p, 0}, {0, -1, p}, {0, 1, p},
                {0, -1, -p}, {0, 1, -p}, {p, 0, -1}, {p, 0, 1}, {-p, 0, -1}, {-p, 0, 1}};
  m.triangles = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      const auto& va = m.vertices[a];
      const auto& vb = m.vertices[b];
      m.vertices.push_back({(va[0] + vb[0]) / 2, (va[1] + vb[1]) / 2, (va[2] + vb[2]) / 2});
      const int id = static_cast<int>(m.vertices.size()) - 1;
      mid.emplace(key, id);
      return id;
    };
    std::vector<std::array<std::int32_t, 3>> next;
    for (const auto& t : m.triangles) {
      const int a = midpoint(t[0], t[1]), b = midpoint(t[1], t[2]), c = midpoint(t[2], t[0]);
      next.push_back({t[0], a, c});
      next.push_back({t[1], b, a});
      next.push_back({t[2], c, b});
      next.push_back({a, b, c});
    }
    m.triangles = std::move(next);
  }
  for (auto& v : m.vertices) {
    const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (auto& x : v) x *= radius / n;
  }
  return m;
}

// Axis-aligned box [lo, hi], 12 triangles, outward.
inline mesh::TriangleMesh BoxMesh(const std::array<double, 3>& lo, const std::array<double, 3>& hi) {
  mesh::TriangleMesh m;
  for (int i = 0; i < 8; ++i) m.vertices.push_back({(i & 1) ? hi[0] : lo[0], (i & 2) ? hi[1] : lo[1], (i & 4) ? hi[2] : lo[2]});
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
