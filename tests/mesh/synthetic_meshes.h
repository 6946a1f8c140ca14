// tests/mesh/synthetic_meshes.h — meshes with known analytic answers.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::mesh::testing {

// Axis-aligned box [x0,x1]x[y0,y1]x[z0,z1], 8 vertices, 12 outward triangles.
inline TriangleMesh Box(double x0, double y0, double z0, double x1, double y1, double z1) {
  TriangleMesh m;
  m.vertices = {{x0, y0, z0}, {x1, y0, z0}, {x1, y1, z0}, {x0, y1, z0},
                {x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}};
  m.triangles = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                 {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  return m;
}

inline TriangleMesh UnitCube() { return Box(0, 0, 0, 1, 1, 1); }

// Appends b to a (indices shifted), no merging.
inline TriangleMesh Concatenate(TriangleMesh a, const TriangleMesh& b) {
  const auto offset = static_cast<std::int32_t>(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (auto t : b.triangles) a.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  return a;
}

// Closed box [0,sx]x[0,sy]x[0,sz] whose every face is an n x n grid of quads
// (2 triangles each), so no face is much larger than the others.
inline TriangleMesh GridBox(double sx, double sy, double sz, int n) {
  TriangleMesh m;
  std::map<std::array<long long, 3>, std::int32_t> index;  // lattice coordinates -> vertex
  auto vertex = [&](long long i, long long j, long long k) {
    auto [it, inserted] =
        index.emplace(std::array<long long, 3>{i, j, k}, static_cast<std::int32_t>(m.vertices.size()));
    if (inserted) m.vertices.push_back({sx * i / n, sy * j / n, sz * k / n});
    return it->second;
  };
  // For each of the 6 faces: axis a fixed at 0 or n, grid over axes b, c with
  // (b, c, a) right-handed so that (b, c) order gives the outward normal at n.
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          std::array<std::int32_t, 4> q;
          const int corner[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
          for (int k = 0; k < 4; ++k) {
            std::array<long long, 3> p{};
            p[a] = side * n;
            p[b] = corner[k][0];
            p[c] = corner[k][1];
            q[k] = vertex(p[0], p[1], p[2]);
          }
          if (side == 1) {
            m.triangles.push_back({q[0], q[1], q[2]});
            m.triangles.push_back({q[0], q[2], q[3]});
          } else {
            m.triangles.push_back({q[0], q[2], q[1]});
            m.triangles.push_back({q[0], q[3], q[2]});
          }
        }
      }
    }
  }
  return m;
}

// Icosphere of the given radius about the origin: the icosahedron with each
// triangle split in four `levels` times, vertices projected onto the sphere.
inline TriangleMesh IcoSphere(double radius, int levels) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  TriangleMesh m;
  m.vertices = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  m.triangles = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> middle;
    auto mid = [&](std::int32_t a, std::int32_t b) {
      auto key = std::minmax(a, b);
      auto it = middle.find(key);
      if (it != middle.end()) return it->second;
      const auto& p = m.vertices[a];
      const auto& q = m.vertices[b];
      m.vertices.push_back({(p[0] + q[0]) / 2, (p[1] + q[1]) / 2, (p[2] + q[2]) / 2});
      const auto id = static_cast<std::int32_t>(m.vertices.size() - 1);
      middle.emplace(key, id);
      return id;
    };
    std::vector<std::array<std::int32_t, 3>> next;
    for (const auto& f : m.triangles) {
      const std::int32_t ab = mid(f[0], f[1]), bc = mid(f[1], f[2]), ca = mid(f[2], f[0]);
      next.push_back({f[0], ab, ca});
      next.push_back({f[1], bc, ab});
      next.push_back({f[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    m.triangles = std::move(next);
  }
  for (auto& p : m.vertices) {
    const double len = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (double& x : p) x *= radius / len;
  }
  return m;
}

}  // namespace fabatlas::mesh::testing
