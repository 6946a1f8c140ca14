// fabatlas/swept/carve.h — carving the swept volume of a moving part out of
// another part (Reconfigurables, section 6.7, Eq. 4):
//
//   A <- A \ offset(sweep(B, f_A^-1 o f_B), eps)
//
// The swept volume is approximated (iso-eps surface of the sparse swept
// distance field, swept_volume.h); the subtraction is exact (CGAL
// Polygon_mesh_processing::corefine_and_compute_difference on
// Surface_mesh<Epick>), so A keeps its details away from the cut.
// Units: millimetres. Single-threaded CGAL; the sweep uses TBB.
#pragma once

#include <vector>

#include "fabatlas/mesh/triangle_mesh.h"
#include "fabatlas/swept/rigid_motion.h"
#include "fabatlas/swept/swept_volume.h"

namespace fabatlas::swept {

// Exact boolean a \ b of two closed, non-self-intersecting, outward triangle
// meshes (mesh::ExactBoolean). Throws InputError if either is not closed,
// not manifold or intersects itself, or CGAL cannot produce a manifold result.
mesh::TriangleMesh Subtract(const mesh::TriangleMesh& a, const mesh::TriangleMesh& b);

// Reconfigurables, Eq. 4: carve from A (moving by motion_a) the eps-offset
// (options.offset) swept volume of B (moving by motion_b) observed in A's
// frame. Returns A's new mesh in A's body coordinates.
mesh::TriangleMesh CarveSweptVolume(const mesh::TriangleMesh& a, const RigidMotion& motion_a,
                                    const mesh::TriangleMesh& b, const RigidMotion& motion_b,
                                    const SweptVolumeOptions& options = {});

// Exact collision test at discrete times: true if the closed meshes A (static)
// and B placed by any of `poses_b` (A's frame <- B's frame) share a point,
// counting containment (CGAL Polygon_mesh_processing::do_intersect).
bool CollidesAtAnyPose(const mesh::TriangleMesh& a, const mesh::TriangleMesh& b, const std::vector<Transform>& poses_b);

}  // namespace fabatlas::swept
