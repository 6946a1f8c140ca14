// Corefinement in doubles (exact_solid.h): CGAL Polygon Mesh Processing's
// corefine_and_compute_* on Surface_mesh<Epick>, the fast first try of every
// exact boolean.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>

#include <optional>
#include <vector>

#include "exact_solid.h"

namespace fabatlas::mesh::internal {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;

using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;
using FloatMesh = CGAL::Surface_mesh<Epick::Point_3>;

// The same surface with its points rounded to doubles (From: back to exact
// points, which doubles are exactly).
template <typename Out, typename In, typename MakePoint>
Out Copied(const In& m, MakePoint make) {
  Out out;
  std::vector<typename Out::Vertex_index> to(m.number_of_vertices() + m.number_of_removed_vertices());
  for (auto v : m.vertices()) to[v.idx()] = out.add_vertex(make(m.point(v)));
  std::vector<typename Out::Vertex_index> face;
  for (auto f : m.faces()) {
    face.clear();
    for (auto v : CGAL::vertices_around_face(m.halfedge(f), m)) face.push_back(to[v.idx()]);
    out.add_face(face);
  }
  return out;
}
FloatMesh ToFloat(const SurfaceMesh& m) {
  return Copied<FloatMesh>(m, [](const Point& p) {
    return Epick::Point_3(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z()));
  });
}
SurfaceMesh FromFloat(const FloatMesh& m) {
  return Copied<SurfaceMesh>(m, [](const Epick::Point_3& p) { return Point(p.x(), p.y(), p.z()); });
}

}  // namespace

// Corefinement with exact predicates and constructions in doubles: the
// intersection points are rounded once as they are made, which is all a
// result rounded to doubles keeps. Taken when the result is closed and does
// not touch itself (rounding can make it), else nullopt. Coplanar faces with
// many crossings (two 360-gon caps in one plane) cost seconds in the exact
// kernel and milliseconds here.
std::optional<SurfaceMesh> FloatCorefinement(BooleanOp op, const SurfaceMesh& a, const SurfaceMesh& b) {
  try {
    FloatMesh fa = ToFloat(a), fb = ToFloat(b), out;
    const auto np = CGAL::parameters::throw_on_self_intersection(true);
    const bool ok = op == BooleanOp::kUnion        ? PMP::corefine_and_compute_union(fa, fb, out, np, np)
                    : op == BooleanOp::kDifference ? PMP::corefine_and_compute_difference(fa, fb, out, np, np)
                                                   : PMP::corefine_and_compute_intersection(fa, fb, out, np, np);
    if (!ok || !CGAL::is_closed(out) || PMP::does_self_intersect(out)) return std::nullopt;
    return FromFloat(out);
  } catch (...) {
    return std::nullopt;
  }
}

}  // namespace fabatlas::mesh::internal
