// A closed mesh's convex parts (exact_solid.h): its hull when it is convex,
// else CGAL's convex decomposition of its Nef polyhedron, as OpenSCAD
// 2021.01 splits Minkowski operands.
#include <CGAL/Nef_polyhedron_3.h>
#include <CGAL/Polyhedron_3.h>
#include <CGAL/convex_decomposition_3.h>

#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "exact_solid.h"
#include "fabatlas/mesh/enclosed_volume.h"
#include "nef_solid.h"

namespace fabatlas::mesh::internal {

std::vector<std::vector<std::array<double, 3>>> ConvexParts(const TriangleMesh& m) {
  const TriangleMesh hull = ConvexHull(m.vertices);
  const double volume = std::abs(EnclosedVolume(m)), hull_volume = std::abs(EnclosedVolume(hull));
  if (hull_volume <= volume * (1 + 1e-9)) return {hull.vertices};  // convex
  Exact e = ToExact(m, 0, BooleanOptions{});
  Nef nef = NefOf(e)->nef;
  CGAL::convex_decomposition_3(nef);
  std::vector<std::vector<std::array<double, 3>>> parts;
  auto volume_it = nef.volumes_begin();
  for (++volume_it; volume_it != nef.volumes_end(); ++volume_it) {
    if (!volume_it->mark()) continue;
    CGAL::Polyhedron_3<Kernel> part;
    nef.convert_inner_shell_to_polyhedron(volume_it->shells_begin(), part);
    std::vector<std::array<double, 3>> points;
    for (auto v = part.vertices_begin(); v != part.vertices_end(); ++v)
      points.push_back(
          {CGAL::to_double(v->point().x()), CGAL::to_double(v->point().y()), CGAL::to_double(v->point().z())});
    if (!points.empty()) parts.push_back(std::move(points));
  }
  return parts;
}

}  // namespace fabatlas::mesh::internal
