// Nef polyhedra (CGAL's Nef_polyhedron_3 on the exact kernel): the exact
// booleans OpenSCAD 2021.01 computes everything with, ExactBoolean's
// fallback where corefinement cannot give a manifold result (exact_solid.h).
// The only file that builds Nef polyhedra and their booleans.
#include <CGAL/Polygon_mesh_processing/bbox.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/boost/graph/convert_nef_polyhedron_to_polygon_mesh.h>

#include <array>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "exact_solid.h"
#include "nef_solid.h"

namespace fabatlas::mesh::internal {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;

// The Nef polyhedron of a closed mesh. CGAL builds each closed shell as a
// solid whatever its orientation, so a cavity (an inward shell inside an
// outward one) would come out filled: the outward shells are joined and the
// inward ones, turned outward, taken away.
Nef NefOfMesh(const SurfaceMesh& mesh) {
  std::vector<SurfaceMesh> shells;
  PMP::split_connected_components(mesh, shells);
  if (shells.size() <= 1) return Nef(mesh);
  Nef solid, cavities;
  for (SurfaceMesh& shell : shells) {
    double six = 0;
    for (auto f : shell.faces()) {
      std::array<Point, 3> p;
      int i = 0;
      for (auto v : CGAL::vertices_around_face(shell.halfedge(f), shell))
        if (i < 3) p[i++] = shell.point(v);
      six += CGAL::to_double(CGAL::determinant(p[0] - CGAL::ORIGIN, p[1] - CGAL::ORIGIN, p[2] - CGAL::ORIGIN));
    }
    if (six < 0) {
      PMP::reverse_face_orientations(shell);
      cavities += Nef(shell);
    } else {
      solid += Nef(shell);
    }
  }
  return solid - cavities;
}

Exact OfNef(Nef nef) {
  Exact out;
  out.empty = nef.is_empty();
  if (out.empty) return out;
  if (nef.is_simple()) {
    CGAL::convert_nef_polyhedron_to_polygon_mesh(nef, out.mesh, /*triangulate_all_faces=*/true);
    out.box = PMP::bbox(out.mesh);
  } else {
    std::vector<Point> points;
    std::vector<std::vector<std::size_t>> polygons;
    CGAL::convert_nef_polyhedron_to_polygon_soup(nef, points, polygons, true);
    out.box = CGAL::bbox_3(points.begin(), points.end());
    out.nef = std::make_shared<const NefSolid>(NefSolid{std::move(nef)});
  }
  return out;
}

}  // namespace

std::shared_ptr<const NefSolid> NefOf(const Exact& e) {
  if (e.nef) return e.nef;
  return std::make_shared<const NefSolid>(NefSolid{NefOfMesh(e.mesh)});
}

Exact NefBoolean(BooleanOp op, const Exact& a, const Exact& b) {
  const Nef na = NefOf(a)->nef, nb = NefOf(b)->nef;
  return OfNef(op == BooleanOp::kUnion ? na + nb : op == BooleanOp::kDifference ? na - nb : na * nb);
}

bool IntersectsItself(const SurfaceMesh& m) { return PMP::does_self_intersect(m); }

std::size_t FaceCount(const NefSolid& nef) { return nef.nef.number_of_facets(); }

void AppendNef(const NefSolid& nef, TriangleMesh& out) {
  std::vector<Point> points;
  std::vector<std::vector<std::size_t>> polygons;
  CGAL::convert_nef_polyhedron_to_polygon_soup(nef.nef, points, polygons, /*triangulate_all_faces=*/true);
  const auto base = static_cast<std::int32_t>(out.vertices.size());
  for (const Point& p : points)
    out.vertices.push_back({CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())});
  for (const auto& f : polygons)
    if (f.size() == 3)
      out.triangles.push_back({base + static_cast<std::int32_t>(f[0]), base + static_cast<std::int32_t>(f[1]),
                               base + static_cast<std::int32_t>(f[2])});
}

}  // namespace fabatlas::mesh::internal
