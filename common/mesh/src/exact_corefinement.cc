// Corefinement with exact constructions (exact_solid.h): CGAL Polygon Mesh
// Processing's corefine_and_compute_* on Surface_mesh<Epeck>, where the
// result in doubles is not closed or touches itself.
#include <CGAL/Polygon_mesh_processing/corefinement.h>

#include <exception>
#include <string>

#include "exact_solid.h"

namespace fabatlas::mesh::internal {

bool ExactCorefinement(BooleanOp op, const SurfaceMesh& a, const SurfaceMesh& b, SurfaceMesh& out, std::string& why) {
  namespace PMP = CGAL::Polygon_mesh_processing;
  SurfaceMesh ma = a, mb = b;
  bool ok = false;
  try {
    const auto np = CGAL::parameters::throw_on_self_intersection(true);
    ok = op == BooleanOp::kUnion        ? PMP::corefine_and_compute_union(ma, mb, out, np, np)
         : op == BooleanOp::kDifference ? PMP::corefine_and_compute_difference(ma, mb, out, np, np)
                                        : PMP::corefine_and_compute_intersection(ma, mb, out, np, np);
    why = "no manifold result";
  } catch (const PMP::Corefinement::Self_intersection_exception&) {
    why = "an operand touches itself near the intersection";
  } catch (const std::exception& e) {
    why = e.what();
  }
  return ok;
}

}  // namespace fabatlas::mesh::internal
