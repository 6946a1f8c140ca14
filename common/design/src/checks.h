// Internal: the validity checks W_F of a design (Fab Forms Sec. 4).
#pragma once

#include <functional>
#include <mutex>

#include "assembly_node.h"
#include "expression.h"
#include "openscad_node.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/design/state_graph.h"
#include "fabatlas/mesh/triangle_mesh.h"
#include "reconfigurable.h"

namespace fabatlas::design {

// What checks look at: the sample's solid, and its mesh, extracted once.
class CheckContext {
 public:
  CheckContext(const Design& design, const geometry::Solid& solid, Scope& scope)
      : design_(design), solid_(solid), scope_(scope) {}
  const Design& design() const { return design_; }
  const geometry::Solid& solid() const { return solid_; }
  const mesh::TriangleMesh& Mesh();
  // The mesh Mesh() extracted, moved out (after the checks); null when no
  // check asked for it.
  std::shared_ptr<const mesh::TriangleMesh> TakeMesh();
  double Number(const CheckSpec& spec, const std::string& name, double fallback);

  // Reconfigurables: an object's solid (body frame) and the resolved
  // transitions, provided by the sample evaluation.
  std::function<geometry::Solid(const std::string&)> object_solid;
  std::function<const std::vector<ResolvedTransition>&()> transitions;
  // Assemblies: the design's `assembly` node solved at this sample.
  std::function<std::shared_ptr<const AssemblyOutcome>()> assembly;
  // Meshes that entered the sample from outside fabatlas (mesh nodes,
  // OpenSCAD polyhedra and renders): what `watertight` inspects in full.
  const std::vector<OutsideMesh>* outside = nullptr;
  // Reconfigurables: where collision_free records what it tested (optional).
  StateGraph* state_graph = nullptr;

 private:
  const Design& design_;
  const geometry::Solid& solid_;
  Scope& scope_;
  std::once_flag mesh_once_;
  bool mesh_made_ = false;
  mesh::TriangleMesh mesh_;
  std::mutex number_mutex_;  // checks running side by side share the scope
};

CheckOutcome RunCheck(const CheckSpec& spec, CheckContext& context);

// Every check of `specs`, outcomes in the same order. The checks that only
// read the sample's solid and its surface (watertight, min_thickness, stands,
// max_volume) run side by side as TBB tasks (their own parallel loops nest),
// after the surface they share has been extracted once (its wall time in
// *surface_seconds when given; 0 when no check reads it); then the others
// (fem, collision_free, assembly_*, target_reached), one after another in the
// design's order. Each outcome's seconds are its own wall time: those of
// checks side by side overlap. An exception of a check is rethrown after the
// side-by-side checks have finished, the first in the design's order.
// The parameters the collision_free check lets automatic resolution change
// (`repair_with: "a, b"`), empty when it names none.
std::vector<std::string> RepairParameters(const Design& design);

std::vector<CheckOutcome> RunChecks(const std::vector<CheckSpec>& specs, CheckContext& context,
                                    double* surface_seconds = nullptr);

// Signed distance (mm) of point p from the boundary of the convex hull of
// `points` in the plane: positive inside, negative outside. Fewer than three
// non-collinear points give a degenerate hull: the distance is then negative
// (a point or segment cannot support a solid).
double DistanceInsideConvexHull(std::vector<geometry::Vec2> points, const geometry::Vec2& p);

}  // namespace fabatlas::design
