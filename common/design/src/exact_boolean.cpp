#include "exact_boolean.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include "operations.h"

namespace fabatlas::design {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;

SurfaceMesh ToSurfaceMesh(const mesh::TriangleMesh& m, std::size_t index) {
  std::vector<Kernel::Point_3> points;
  for (const auto& v : m.vertices) points.emplace_back(v[0], v[1], v[2]);
  std::vector<std::vector<std::size_t>> faces;
  for (const auto& t : m.triangles) faces.push_back({std::size_t(t[0]), std::size_t(t[1]), std::size_t(t[2])});
  SurfaceMesh out;
  if (!PMP::is_polygon_soup_a_polygon_mesh(faces))
    throw SampleFailure("no_geometry", "exact boolean operand " + std::to_string(index) + " is not a manifold mesh");
  PMP::polygon_soup_to_polygon_mesh(points, faces, out);
  if (!CGAL::is_closed(out))
    throw SampleFailure("no_geometry", "exact boolean operand " + std::to_string(index) + " is not closed");
  if (PMP::does_self_intersect(out))
    throw SampleFailure("no_geometry", "exact boolean operand " + std::to_string(index) + " intersects itself");
  return out;
}

mesh::TriangleMesh FromSurfaceMesh(const SurfaceMesh& m) {
  mesh::TriangleMesh out;
  std::map<SurfaceMesh::Vertex_index, std::int32_t> index;
  for (auto v : m.vertices()) {
    index[v] = static_cast<std::int32_t>(out.vertices.size());
    const auto& p = m.point(v);
    out.vertices.push_back({p.x(), p.y(), p.z()});
  }
  for (auto f : m.faces()) {
    std::array<std::int32_t, 3> tri{};
    int i = 0;
    for (auto v : CGAL::vertices_around_face(m.halfedge(f), m)) {
      if (i < 3) tri[i] = index[v];
      ++i;
    }
    if (i == 3) out.triangles.push_back(tri);
  }
  return out;
}

}  // namespace

mesh::TriangleMesh ExactMeshBoolean(const std::string& op, const std::vector<mesh::TriangleMesh>& operands) {
  SurfaceMesh acc = ToSurfaceMesh(operands.at(0), 0);
  for (std::size_t i = 1; i < operands.size(); ++i) {
    SurfaceMesh other = ToSurfaceMesh(operands[i], i);
    SurfaceMesh result;
    bool ok = op == "union"        ? PMP::corefine_and_compute_union(acc, other, result)
              : op == "difference" ? PMP::corefine_and_compute_difference(acc, other, result)
                                   : PMP::corefine_and_compute_intersection(acc, other, result);
    if (!ok) throw SampleFailure("no_geometry", "exact " + op + " with operand " + std::to_string(i) + " has no manifold result");
    acc = std::move(result);
  }
  return FromSurfaceMesh(acc);
}

geometry::Solid ExactBoolean(const std::string& op, const std::vector<geometry::Solid>& children,
                             const geometry::GridSpec& grid) {
  std::vector<mesh::TriangleMesh> meshes;
  for (const auto& c : children) meshes.push_back(c.ToMesh());
  mesh::TriangleMesh result = ExactMeshBoolean(op, meshes);
  if (result.triangles.empty()) return geometry::Solid();
  return geometry::FromMesh(grid, result);
}

}  // namespace fabatlas::design
