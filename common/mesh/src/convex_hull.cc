// ConvexHull (exact_boolean.h): CGAL's convex_hull_3 with exact predicates.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "fabatlas/mesh/exact_boolean.h"

namespace fabatlas::mesh {

TriangleMesh ConvexHull(const std::vector<std::array<double, 3>>& points) {
  using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;
  std::vector<Epick::Point_3> p;
  p.reserve(points.size());
  for (const auto& v : points)
    if (std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2])) p.emplace_back(v[0], v[1], v[2]);
  // The points span a volume when four of them are not coplanar.
  std::size_t second = 1, third = 0, fourth = 0;
  while (second < p.size() && p[second] == p[0]) ++second;
  for (std::size_t i = second + 1; i < p.size() && !third; ++i)
    if (!CGAL::collinear(p[0], p[second], p[i])) third = i;
  for (std::size_t i = third + 1; third && i < p.size() && !fourth; ++i)
    if (CGAL::orientation(p[0], p[second], p[third], p[i]) != CGAL::COPLANAR) fourth = i;
  TriangleMesh out;
  if (!fourth) return out;
  CGAL::Surface_mesh<Epick::Point_3> hull;
  CGAL::convex_hull_3(p.begin(), p.end(), hull);
  std::vector<std::int32_t> index(hull.number_of_vertices() + hull.number_of_removed_vertices(), -1);
  for (auto v : hull.vertices()) {
    index[v.idx()] = static_cast<std::int32_t>(out.vertices.size());
    const auto& q = hull.point(v);
    out.vertices.push_back({q.x(), q.y(), q.z()});
  }
  for (auto f : hull.faces()) {
    std::array<std::int32_t, 3> tri{};
    int i = 0;
    for (auto v : CGAL::vertices_around_face(hull.halfedge(f), hull))
      if (i < 3) tri[i++] = index[v.idx()];
    out.triangles.push_back(tri);
  }
  return out;
}

}  // namespace fabatlas::mesh
