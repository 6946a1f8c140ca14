// Exact mesh booleans by CGAL corefinement (see exact_boolean.h).
#include "fabatlas/mesh/exact_boolean.h"

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include "fabatlas/error.h"

namespace fabatlas::mesh {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;

SurfaceMesh ToSurfaceMesh(const TriangleMesh& m, std::size_t index) {
  std::vector<Kernel::Point_3> points;
  for (const auto& v : m.vertices) points.emplace_back(v[0], v[1], v[2]);
  std::vector<std::vector<std::size_t>> faces;
  for (const auto& t : m.triangles) {
    for (std::int32_t v : t)
      if (v < 0 || static_cast<std::size_t>(v) >= m.vertices.size())
        throw InputError("exact boolean operand " + std::to_string(index) + " has a triangle with a missing vertex");
    faces.push_back({std::size_t(t[0]), std::size_t(t[1]), std::size_t(t[2])});
  }
  SurfaceMesh out;
  if (!PMP::is_polygon_soup_a_polygon_mesh(faces))
    throw InputError("exact boolean operand " + std::to_string(index) + " is not a manifold mesh");
  PMP::polygon_soup_to_polygon_mesh(points, faces, out);
  if (!CGAL::is_closed(out))
    throw InputError("exact boolean operand " + std::to_string(index) + " is not closed");
  if (PMP::does_self_intersect(out))
    throw InputError("exact boolean operand " + std::to_string(index) + " intersects itself");
  return out;
}

TriangleMesh FromSurfaceMesh(const SurfaceMesh& m) {
  TriangleMesh out;
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

const char* BooleanOpName(BooleanOp op) {
  switch (op) {
    case BooleanOp::kUnion: return "union";
    case BooleanOp::kDifference: return "difference";
    case BooleanOp::kIntersection: return "intersection";
  }
  return "union";
}

TriangleMesh ExactBoolean(BooleanOp op, const std::vector<TriangleMesh>& operands) {
  const std::string name = BooleanOpName(op);
  SurfaceMesh acc = ToSurfaceMesh(operands.at(0), 0);
  for (std::size_t i = 1; i < operands.size(); ++i) {
    SurfaceMesh other = ToSurfaceMesh(operands[i], i);
    SurfaceMesh result;
    bool ok = false;
    try {
      ok = op == BooleanOp::kUnion        ? PMP::corefine_and_compute_union(acc, other, result)
           : op == BooleanOp::kDifference ? PMP::corefine_and_compute_difference(acc, other, result)
                                          : PMP::corefine_and_compute_intersection(acc, other, result);
    } catch (const std::exception& e) {  // CGAL's own checks (degenerate or inconsistent input)
      throw InputError("exact " + name + " with operand " + std::to_string(i) + " failed: " + e.what());
    }
    if (!ok) throw InputError("exact " + name + " with operand " + std::to_string(i) + " has no manifold result");
    acc = std::move(result);
  }
  return FromSurfaceMesh(acc);
}

}  // namespace fabatlas::mesh
