// EvaluateSample (Fab Forms Alg. 2) step by step: constraints, the tree's
// geometry (tree_evaluation.h), the checks, the state graph of
// reconfigurables, repairable collisions, properties; and ΔG (Eq. 2).
#include "fabatlas/design/evaluate_sample.h"

#include <memory>
#include <sstream>

#include "checks.h"
#include "expression.h"
#include "fabatlas/design/resolve_collisions.h"
#include "fabatlas/design/state_graph.h"
#include "fabatlas/error.h"
#include "fabatlas/mesh/surface_area.h"
#include "fabatlas/stopwatch.h"
#include "reconfigurable.h"
#include "tree_evaluation.h"

namespace fabatlas::design {
namespace {

// Records the sample's failure unless it has one (the first one found
// names it).
void Fail(SampleResult& r, const std::string& type, const std::string& reason) {
  if (r.failure.empty()) {
    r.failure = type;
    r.failure_reason = reason;
  }
}

// Lines 1–3: fix exposed parameters, solve constraints; the "constraints"
// check.
ConstraintSolveSummary SolveAt(const Design& design, const Point& u, SampleResult& r) {
  ConstraintSolveSummary solve = SolveConstraints(design, u);
  r.values = solve.values;
  r.timings["solve"] = solve.seconds;
  CheckOutcome constraints{"constraints", solve.satisfiable, "", "", solve.seconds};
  if (!solve.satisfiable) {
    constraints.failure = kUnsatConstraints;
    std::ostringstream reason;
    reason << "constraint '" << solve.worst_constraint << "' stays violated by " << solve.max_violation;
    constraints.reason = reason.str();
    Fail(r, kUnsatConstraints, constraints.reason);
  }
  r.checks.push_back(constraints);
  return solve;
}

// Lines 7–9: evaluate the tree (with cached subtrees) into r.solid (and
// options.parts); the "geometry" check. Whether it passed.
bool EvaluateGeometry(const Design& design, TreeEvaluation& tree, const EvaluateOptions& options, SampleResult& r) {
  const Stopwatch tree_start;
  CheckOutcome geometry_check{"geometry", true, "", "", 0};
  std::string geometry_failure = kNoGeometry;
  try {
    if (options.parts) options.parts->clear();
    r.solid = tree.Evaluate(design.tree, "root").solid;
    r.warnings = tree.Warnings();
    if (options.parts && options.parts->empty() && !r.solid.empty()) {
      Part whole;
      whole.name = "body1";
      whole.mesh = r.solid.ToMesh();
      options.parts->push_back(std::move(whole));
    }
    if (r.solid.empty()) {
      geometry_check.passed = false;
      geometry_check.reason = "the tree produced no material";
    }
  } catch (const SampleFailure& e) {
    geometry_check.passed = false;
    geometry_check.reason = e.what();
    geometry_failure = e.type();  // e.g. unsat_constraints from a prototype node
  } catch (const ResourceError&) {
    throw;
  } catch (const DesignFault&) {
    throw;
  } catch (const InputError& e) {
    // Out-of-range values at this point (e.g. a negative radius).
    geometry_check.passed = false;
    geometry_check.reason = e.what();
  }
  geometry_check.seconds = r.timings["tree"] = tree_start.Seconds();
  if (!geometry_check.passed) {
    geometry_check.failure = geometry_failure;
    Fail(r, geometry_failure, geometry_check.reason);
    r.solid = geometry::Solid();
    if (options.parts) options.parts->clear();
  }
  r.checks.push_back(geometry_check);
  return geometry_check.passed;
}

// Lines 10–15: every test w_i. Returns the surface the checks extracted
// (null when none read it).
std::shared_ptr<const mesh::TriangleMesh> RunSampleChecks(const Design& design, Scope& scope, TreeEvaluation& tree,
                                                          const EvaluateOptions& options, SampleResult& r) {
  const Stopwatch checks_start;
  CheckContext context(design, r.solid, scope);
  // Objects first evaluated by a check are recorded apart: the subtree
  // records stay the tree's, root last.
  std::vector<SubtreeRecord> check_records;
  tree.RecordInto(&check_records);
  context.object_solid = [&](const std::string& name) { return tree.EvaluateObject(name).solid; };
  context.transitions = [&]() -> const std::vector<ResolvedTransition>& { return tree.Transitions(); };
  context.assembly = [&]() { return tree.Assembly(); };
  context.outside = &tree.Outside();
  context.state_graph = options.state_graph;
  double surface_seconds = 0;
  for (CheckOutcome& outcome : RunChecks(design.checks, context, &surface_seconds)) {
    if (!outcome.passed) Fail(r, outcome.failure, outcome.reason);
    r.checks.push_back(std::move(outcome));
  }
  if (surface_seconds > 0) r.timings["surface"] = surface_seconds;
  r.timings["checks"] = checks_start.Seconds();
  std::shared_ptr<const mesh::TriangleMesh> surface = context.TakeMesh();
  if (options.keep_surface) r.surface = surface;
  return surface;
}

// Reconfigurables: what a collision_free check did not record (no such
// check, or checks skipped): the objects and motions, without collisions.
void RecordObjectsAndMotions(const Design& design, TreeEvaluation& tree, StateGraph& g, SampleResult& r) {
  g.object_names.clear();
  for (const auto& object : design.objects) g.object_names.push_back(object.name);
  try {
    if (g.objects.empty())
      for (const auto& object : design.objects) g.objects.push_back(tree.EvaluateObject(object.name).solid.ToMesh());
    {
      const auto& resolved = tree.Transitions();
      for (std::size_t k = g.transitions.size(); k < resolved.size(); ++k)
        g.transitions.push_back(
            {resolved[k].name, design.transitions[k].from, design.transitions[k].to, resolved[k].motions, {}});
    }
  } catch (const SampleFailure& e) {
    Fail(r, e.type(), e.what());
    g = StateGraph{};
  }
}

// Lines 7–15 at the solved parameter values: the geometry, then (when it
// has material) the checks and the state graph. Returns the surface the
// checks extracted (null when none read it).
std::shared_ptr<const mesh::TriangleMesh> EvaluateAtValues(const Design& design, const ConstraintSolveSummary& solve,
                                                           const EvaluateOptions& options, SampleResult& r) {
  Scope scope(ParameterNames(design));
  for (const auto& [name, value] : solve.values) scope.Set(name, value);
  // Kept for the checks: collision_free evaluates the objects (cached).
  TreeEvaluation tree(design, scope, options, r.subtrees);
  const bool has_geometry = EvaluateGeometry(design, tree, options, r);
  std::shared_ptr<const mesh::TriangleMesh> surface;
  if (has_geometry && options.run_checks) surface = RunSampleChecks(design, scope, tree, options, r);
  if (has_geometry && options.state_graph && !design.objects.empty())
    RecordObjectsAndMotions(design, tree, *options.state_graph, r);
  return surface;
}

// Reconfigurables, Sec. 6.6: a collision the design declares repairable
// (collision_free's `repair_with`) and automatic resolution within those
// parameters resolves, proved by every check at the resolved point, makes
// the sample's failure `repairable`.
void MarkRepairable(const Design& design, const Point& u, SampleResult& r) {
  const std::vector<std::string> with = RepairParameters(design);
  if (with.empty()) return;
  ResolutionOptions ro;
  ro.parameters = with;
  const ResolveSummary s = ResolveCollisions(design, u, ro);
  if (!s.resolved) return;
  std::ostringstream reason;
  reason.precision(4);
  reason << r.failure_reason << "; repairable:";
  for (const auto& [name, d] : s.edit) reason << " " << name << (d >= 0 ? " +" : " ") << d;
  reason << " resolves it";
  r.failure = kRepairable;
  r.failure_reason = reason.str();
}

// Lines 16–19: properties of a valid sample; `surface` the checks' (null:
// extracted here when `area` needs it).
void ComputeProperties(const Design& design, const mesh::TriangleMesh* surface, SampleResult& r) {
  const Stopwatch props_start;
  for (const std::string& name : design.properties) {
    if (name == "volume") {
      r.properties["volume"] = r.solid.Volume();
    } else if (name == "bbox") {
      geometry::Box3 box = r.solid.BoundingBox();
      r.properties["bbox_x"] = box.max[0] - box.min[0];
      r.properties["bbox_y"] = box.max[1] - box.min[1];
      r.properties["bbox_z"] = box.max[2] - box.min[2];
    } else if (name == "area") {
      r.properties["area"] = mesh::SurfaceArea(surface ? *surface : r.solid.ToMesh());
    }
  }
  for (const CheckOutcome& c : r.checks)
    for (const auto& [name, value] : c.measures) r.properties[name] = value;
  r.timings["properties"] = props_start.Seconds();
}

}  // namespace

SampleResult EvaluateSample(const Design& design, const Point& u, const EvaluateOptions& options) {
  const Stopwatch start;
  SampleResult r;
  r.u = u;
  const ConstraintSolveSummary solve = SolveAt(design, u, r);
  // The surface the checks extracted (null when none read it): the `area`
  // property and EvaluateOptions::keep_surface take it instead of extracting
  // it again.
  std::shared_ptr<const mesh::TriangleMesh> surface;
  if (solve.satisfiable) surface = EvaluateAtValues(design, solve, options, r);
  if (r.failure == kCollision && options.run_checks && options.repair_collisions) MarkRepairable(design, u, r);
  r.valid = r.failure.empty();
  if (r.valid && options.run_checks) ComputeProperties(design, surface.get(), r);
  if (!options.keep_solid) r.solid = geometry::Solid();
  r.timings["total"] = start.Seconds();
  return r;
}

double DeltaG(const SampleResult& a, const SampleResult& b) {
  if (!a.valid && !b.valid) return 0.0;
  if (a.valid != b.valid) return 1.0;
  return geometry::DeltaG(a.solid, b.solid);
}

}  // namespace fabatlas::design
