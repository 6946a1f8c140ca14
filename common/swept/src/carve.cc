// Exact carving of a swept volume with CGAL corefinement (Reconfigurables, Eq. 4).
#include "fabatlas/swept/carve.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/intersection.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Surface_mesh.h>

#include <string>

#include "fabatlas/error.h"
#include "fabatlas/mesh/exact_boolean.h"

namespace fabatlas::swept {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Surface = CGAL::Surface_mesh<Point>;
namespace PMP = CGAL::Polygon_mesh_processing;

Surface ToSurface(const mesh::TriangleMesh& m, const Transform* f, const char* what) {
  Surface s;
  std::vector<Surface::Vertex_index> ids;
  ids.reserve(m.vertices.size());
  for (const auto& v : m.vertices) {
    const Vec3 p = f ? f->Apply(v) : v;
    ids.push_back(s.add_vertex(Point(p[0], p[1], p[2])));
  }
  const auto nv = static_cast<std::int64_t>(m.vertices.size());
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const auto& tri = m.triangles[t];
    for (int k = 0; k < 3; ++k) {
      if (tri[k] < 0 || tri[k] >= nv) {
        throw InputError(std::string(what) + ": triangle " + std::to_string(t) + " refers to a missing vertex");
      }
    }
    if (s.add_face(ids[tri[0]], ids[tri[1]], ids[tri[2]]) == Surface::null_face()) {
      throw InputError(std::string(what) + ": triangle " + std::to_string(t) + " makes the mesh non-manifold");
    }
  }
  if (s.is_empty() || !CGAL::is_closed(s)) throw InputError(std::string(what) + ": mesh is not closed");
  return s;
}

}  // namespace

mesh::TriangleMesh Subtract(const mesh::TriangleMesh& a, const mesh::TriangleMesh& b) {
  return mesh::ExactBoolean(mesh::BooleanOp::kDifference, {a, b});
}

mesh::TriangleMesh CarveSweptVolume(const mesh::TriangleMesh& a, const RigidMotion& motion_a,
                                    const mesh::TriangleMesh& b, const RigidMotion& motion_b,
                                    const SweptVolumeOptions& options) {
  // Relative motion of B observed in A's frame, f_A^-1 o f_B.
  const auto poses = SamplePoses(
      b, [&](double t) { return motion_a.At(t).Inverse().Compose(motion_b.At(t)); }, options);
  const SweptDistanceField field = ComputeSweptDistance(b, poses, options);
  return Subtract(a, field.Surface(options.offset));
}

bool CollidesAtAnyPose(const mesh::TriangleMesh& a, const mesh::TriangleMesh& b,
                       const std::vector<Transform>& poses_b) {
  const Surface sa = ToSurface(a, nullptr, "collision: part A");
  for (const auto& f : poses_b) {
    const Surface sb = ToSurface(b, &f, "collision: part B");
    if (PMP::do_intersect(sa, sb, CGAL::parameters::do_overlap_test_of_bounded_sides(true),
                          CGAL::parameters::do_overlap_test_of_bounded_sides(true))) {
      return true;
    }
  }
  return false;
}

}  // namespace fabatlas::swept
