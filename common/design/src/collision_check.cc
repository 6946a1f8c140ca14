// The collision_free check of a reconfigurable design: every transition swept
// in spacetime, the first collision and the clearance (Reconfigurables Sec. 5;
// docs/swept.md).

#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include "check_kinds.h"
#include "checks.h"
#include "fabatlas/error.h"
#include "fabatlas/swept/spacetime_clearance.h"
#include "fabatlas/swept/spacetime_collision.h"

namespace fabatlas::design {
namespace {

// A collision interval found on one transition.
struct CollisionHit {
  std::string transition;
  swept::CollisionInterval interval;
};

// What sweeping every transition found: its collision intervals, and the
// minimum clearance (0 when something collides, infinite with fewer than two
// objects) with where it is ("transition T: 'a' and 'b' at t = ...").
struct TransitionSweeps {
  std::vector<CollisionHit> hits;
  double clearance = std::numeric_limits<double>::infinity();
  std::string closest;
};

// Every object's solid as a mesh; a SampleFailure when one has no material.
std::vector<mesh::TriangleMesh> ObjectMeshes(CheckContext& c) {
  std::vector<mesh::TriangleMesh> meshes;
  for (const auto& object : c.design().objects) {
    geometry::Solid solid = c.object_solid(object.name);
    if (solid.empty()) throw SampleFailure(kNoGeometry, "object '" + object.name + "' has no material");
    meshes.push_back(solid.ToMesh());
  }
  return meshes;
}

// Sweeps transition t (collisions, then the clearance when there are none)
// into s, and records it in the state graph when one is asked for. The
// reason the collisions cannot be tested, or nullopt.
std::optional<std::string> SweepTransition(CheckContext& c, const ResolvedTransition& t,
                                           const std::vector<mesh::TriangleMesh>& meshes, int steps,
                                           TransitionSweeps& s) {
  const auto& objects = c.design().objects;
  std::vector<swept::MovingPart> parts;
  for (std::size_t i = 0; i < objects.size(); ++i) parts.push_back({meshes[i], t.motions[i]});
  swept::SpacetimeOptions so;
  so.time_steps = steps;
  swept::CollisionReport report;
  try {
    report = swept::DetectCollisions(parts, so);
  } catch (const InputError& e) {
    // Level-set meshes are closed; a non-manifold one comes from a feature
    // thinner than a voxel.
    return std::string("cannot test collisions: ") + e.what();
  }
  for (const auto& i : report.intervals) s.hits.push_back({t.name, i});
  if (c.state_graph) {
    const std::size_t k = c.state_graph->transitions.size();
    const Transition& edge = c.design().transitions.at(k);
    c.state_graph->transitions.push_back({t.name, edge.from, edge.to, t.motions, report.intervals});
  }
  if (!report.collision_free()) {
    s.clearance = 0;
    return std::nullopt;
  }
  swept::ClearanceOptions co;
  co.time_steps = steps;
  const swept::ClearanceReport cr = swept::MinimumClearance(parts, co);
  if (cr.min_clearance < s.clearance) {
    s.clearance = cr.min_clearance;
    std::ostringstream m;
    m.precision(4);
    m << "transition " << t.name << ": '" << objects[cr.part_a].name << "' and '" << objects[cr.part_b].name
      << "' at t = " << cr.t;
    s.closest = m.str();
  }
  return std::nullopt;
}

// The collision check's outcome from its sweeps: the first three collision
// intervals by when (time span, then transition order), then where; or the
// clearance against the `required` one.
CheckOutcome CollisionOutcome(TransitionSweeps& s, const std::vector<DesignObject>& objects, double required) {
  auto& hits = s.hits;
  std::stable_sort(hits.begin(), hits.end(), [](const CollisionHit& a, const CollisionHit& b) {
    return a.interval.t_begin < b.interval.t_begin;
  });
  CheckOutcome o;
  std::ostringstream reason;
  reason.precision(4);
  if (!hits.empty()) {
    o.failure = kCollision;
    reason << hits.size() << " collision interval" << (hits.size() > 1 ? "s" : "") << ": ";
    for (std::size_t k = 0; k < hits.size() && k < 3; ++k) {
      const auto& h = hits[k];
      const auto& w = h.interval.where;
      reason << (k ? "; " : "") << "transition " << h.transition << " t in [" << h.interval.t_begin << ", "
             << h.interval.t_end << "]: '" << objects[h.interval.part_a].name << "' and '"
             << objects[h.interval.part_b].name << "' in x [" << w.min[0] << ", " << w.max[0] << "] y [" << w.min[1]
             << ", " << w.max[1] << "] z [" << w.min[2] << ", " << w.max[2] << "] mm";
    }
    if (hits.size() > 3) reason << "; and " << hits.size() - 3 << " more";
    // The first interval in numbers (properties are kept for valid samples
    // only, so these reach reports and tests through the outcome).
    o.measures["collision_t_begin"] = hits[0].interval.t_begin;
    o.measures["collision_t_end"] = hits[0].interval.t_end;
  } else {
    if (std::isfinite(s.clearance))
      reason << "min clearance " << s.clearance << " mm (" << s.closest << ")";
    else
      reason << "no two objects (clearance unbounded)";
    if (s.clearance < required) {
      o.failure = kTooLittleClearance;
      reason << " is below " << required << " mm";
    }
  }
  o.passed = o.failure.empty();
  o.reason = reason.str();
  if (std::isfinite(s.clearance)) o.measures["min_clearance"] = s.clearance;
  return o;
}

}  // namespace

namespace check {

// Reconfigurables, section 5: every transition of the state graph is collision-free.
// For each transition, every object moves by its resolved motion; collision
// intervals are found by swept::DetectCollisions (spacetime proxies in a
// bounding volume hierarchy, exact tests at the samples) and reported first
// by when (time span), then where (objects and box). The minimum clearance
// over all transitions (swept::MinimumClearance; 0 when something collides)
// is the measure `min_clearance`; with `clearance` > 0 the check also fails
// when objects come closer than that.
CheckOutcome CollisionFree(const CheckSpec& spec, CheckContext& c) {
  const std::string where = spec.place.str() + ": check '" + spec.name + "'";
  const double steps = c.Number(spec, "time_steps", 101);
  if (!(steps >= 2 && steps <= 100000) || steps != std::round(steps))
    throw InputError(where + ": 'time_steps' must be a whole number in [2, 100000]");
  const double required = c.Number(spec, "clearance", 0);
  if (!std::isfinite(required) || required < 0) throw InputError(where + ": 'clearance' must be >= 0 mm");
  CheckOutcome o;
  std::vector<mesh::TriangleMesh> meshes;
  try {
    meshes = ObjectMeshes(c);
  } catch (const SampleFailure& e) {
    o.failure = kNoGeometry;
    o.reason = e.what();
    return o;
  }
  if (c.state_graph) {
    c.state_graph->collisions_checked = true;
    c.state_graph->time_steps = static_cast<int>(steps);
    c.state_graph->objects = meshes;
    c.state_graph->transitions.clear();
  }
  TransitionSweeps sweeps;
  for (const ResolvedTransition& t : c.transitions())
    if (auto untestable = SweepTransition(c, t, meshes, static_cast<int>(steps), sweeps)) {
      o.failure = kNotWatertight;
      o.reason = *untestable;
      return o;
    }
  return CollisionOutcome(sweeps, c.design().objects, required);
}

}  // namespace check

}  // namespace fabatlas::design
