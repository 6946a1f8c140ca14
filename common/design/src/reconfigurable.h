// Internal: the objects, motions and checks of reconfigurable designs
// (Reconfigurables Secs. 3, 5 and 6.7; docs/design-format.md "Reconfigurables").
#pragma once

#include <string>
#include <vector>

#include "expression.h"
#include "fabatlas/design/design.h"
#include "fabatlas/geometry/solid.h"
#include "fabatlas/mesh/triangle_mesh.h"
#include "fabatlas/swept/rigid_motion.h"
#include "fabatlas/swept/swept_volume.h"

namespace fabatlas::design {

// Every object's motion (body -> world) along one transition. Objects the
// transition does not move hold the pose of the `from` state.
struct ResolvedTransition {
  std::string name;
  std::vector<swept::RigidMotion> motions;  // parallel to Design::objects
  // Canonical text of each object's resolved motion (17 significant
  // digits), for subtree keys.
  std::vector<std::string> canonical;
};

// Resolves the transitions' expressions at the current scope values and
// propagates the state poses (first state: every object at its body frame).
// Non-finite values raise SampleFailure (no_geometry).
std::vector<ResolvedTransition> ResolveTransitions(const Design& design, Scope& scope);

// Index of an object in design.objects (the name was linted at load).
std::size_t ObjectIndex(const Design& design, const std::string& name);

// The eps-offset swept volume of `moving` (body frame) under
// f_frame^-1 o f_moving as a closed mesh (the cutter of CarveSwept).
mesh::TriangleMesh SweptCutter(const geometry::Solid& moving, const swept::RigidMotion& f_moving,
                               const swept::RigidMotion& f_frame, double offset, int time_steps,
                               const geometry::GridSpec& g, const SourcePlace& place,
                               swept::SweptVolumeSummary* summary);

// What one carve did (for benchmarks and tests).
struct CarveSweptSummary {
  std::size_t cutter_triangles = 0;  // of the eps-offset swept surface
  std::size_t target_triangles = 0;  // of the meshed target (exact carving only)
  double sweep_seconds = 0;          // swept distance field and its surface
  double subtract_seconds = 0;       // the subtraction, back to a level set
};

// Reconfigurables, Eq. 4: `target` minus the eps-offset swept volume of `moving`
// (body frame) under f_frame^-1 o f_moving, on grid g. At least `time_steps`
// samples, more until no point moves more than a voxel per step
// (swept::SamplePoses). exact = true (the default of the carve_swept node):
// the target's mesh minus the cutter mesh by CGAL corefinement
// (ExactMeshBoolean), the result re-voxelised on g; exact = false: the
// level-set difference of the cutter re-voxelised on g. Throws SampleFailure
// when moving is empty, offset < 0, or (exact) a mesh is not closed and
// manifold, intersects itself, or CGAL finds no manifold result.
geometry::Solid CarveSwept(const geometry::Solid& target, const geometry::Solid& moving,
                           const swept::RigidMotion& f_moving, const swept::RigidMotion& f_frame, double offset,
                           int time_steps, const geometry::GridSpec& g, const SourcePlace& place, bool exact = true,
                           CarveSweptSummary* summary = nullptr);

}  // namespace fabatlas::design
