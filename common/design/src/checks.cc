#include "checks.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>

#include <tbb/task_group.h>

#include "convex_hull_2d.h"
#include "fabatlas/error.h"
#include "fabatlas/fem/fem_check.h"
#include "fabatlas/geometry/folded_triangles.h"
#include "fabatlas/mesh/mesh_report.h"
#include "fabatlas/mesh/shape_diameter.h"
#include "fabatlas/mesh/surface_area.h"
#include "fabatlas/swept/spacetime_clearance.h"
#include "fabatlas/swept/spacetime_collision.h"
#include "operations.h"

namespace fabatlas::design {
namespace {

std::string Mm(double v) {
  std::ostringstream s;
  s.precision(3);
  s << v << " mm";
  return s.str();
}

double Cross(const geometry::Vec2& o, const geometry::Vec2& a, const geometry::Vec2& b) {
  return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

// Watertight, manifold, not self-intersecting — checked where it can fail:
//  - every mesh that came from outside fabatlas (a mesh node's file, an
//    OpenSCAD polyhedron or render) gets the full test (CGAL, with
//    self-intersections), its defects named; reports are remembered per
//    mesh content for the process, so a mesh is inspected once;
//  - a mesh solid's boundary (the mesh road of OpenSCAD models: exact
//    booleans of the model's own faces, rounded to doubles; Nef results
//    where two parts share only an edge) gets the full test too: it can be
//    non-manifold, and rounding can make it touch itself;
//  - the sample's own level-set extraction is closed and manifold by
//    construction, so what it gets is the cheap test of what it can get
//    wrong: no triangle folded against the level set's outward direction
//    where a part is thinner than a voxel (geometry/folded_triangles.h;
//    docs/mesh.md, "Which check runs where").
CheckOutcome Watertight(CheckContext& c) {
  CheckOutcome o;
  o.passed = true;
  if (c.outside) {
    static std::mutex mutex;
    static std::map<std::string, mesh::MeshReport> reports;
    for (const OutsideMesh& m : *c.outside) {
      mesh::MeshReport report;
      bool known = false;
      {
        std::lock_guard<std::mutex> lock(mutex);
        auto it = reports.find(m.key);
        if (it != reports.end()) {
          report = it->second;
          known = true;
        }
      }
      if (!known) {
        report = mesh::InspectMesh(*m.mesh);
        std::lock_guard<std::mutex> lock(mutex);
        if (reports.size() < 100000) reports[m.key] = report;
      }
      if (!report.closed || !report.manifold || report.self_intersecting) {
        o.passed = false;
        o.failure = !report.closed || !report.manifold ? kNotWatertight : kSelfIntersecting;
        o.reason = m.what + ": " + report.Reasons();
        return o;
      }
    }
  }
  if (const mesh::TriangleMesh* boundary = c.solid().boundary()) {
    const mesh::MeshReport report = mesh::InspectMesh(*boundary);
    if (!report.closed || !report.manifold || report.self_intersecting) {
      o.passed = false;
      o.failure = !report.closed || !report.manifold ? kNotWatertight : kSelfIntersecting;
      o.reason = "the model's exact surface: " + report.Reasons();
    }
    return o;
  }
  // Folds covering less than one voxel face (a single triangle at the tip of
  // a sharp wedge) are below what the grid resolves at all; more is a part
  // the sample's surface does not represent.
  const geometry::FoldedTriangles folds = geometry::FindFoldedTriangles(c.solid(), c.Mesh());
  const double voxel = c.solid().voxel_size();
  if (folds.area > voxel * voxel) {
    char where[200];
    std::snprintf(where, sizeof where,
                  "first near (%.4g, %.4g, %.4g) mm): a part there is thinner than a voxel (%g mm)", folds.first[0],
                  folds.first[1], folds.first[2], voxel);
    o.passed = false;
    o.failure = kThinParts;  // the model's cause; the fold is what it does to our surface
    o.reason = "the level-set surface folds over itself at " + std::to_string(folds.count) + " triangle" +
               (folds.count == 1 ? "" : "s") + " (" + where + "; a smaller voxel_size resolves it";
  }
  return o;
}

// No excessively thin features. method sdf (default): the shape diameter
// function of Shapira et al. 2008, as Fab Forms Table 2 uses; passes when the
// share of surface area thinner than `value` is at most max_thin_fraction
// (default 0.01). method opening: morphological opening of the level set by a
// ball of diameter `value`; passes when the volume lost is at most
// max_thin_fraction (default 0.02, sharp convex edges always lose a little).
CheckOutcome MinThickness(const CheckSpec& spec, CheckContext& c) {
  double value = c.Number(spec, "value", 1.0);
  auto method_it = spec.args.find("method");
  std::string method = method_it == spec.args.end() ? "sdf" : method_it->second.text;
  CheckOutcome o;
  o.failure = kThinParts;
  std::ostringstream reason;
  if (method == "opening") {
    double allowed = c.Number(spec, "max_thin_fraction", 0.02);
    double lost = geometry::OpeningLossFraction(c.solid(), value);
    o.passed = lost <= allowed;
    reason << 100 * lost << "% of the volume is thinner than " << Mm(value) << " (allowed " << 100 * allowed << "%)";
  } else {
    double allowed = c.Number(spec, "max_thin_fraction", 0.01);
    mesh::ShapeDiameterOptions options;
    options.thin_threshold = value;
    // A fixed-stride sample of 4,000 faces estimates the area fractions to
    // ~0.2% (against every face's, docs/mesh.md); the rays are most of the
    // check's cost.
    options.max_faces = 4000;
    mesh::ShapeDiameterSummary sdf = mesh::ShapeDiameter(c.Mesh(), options);
    o.passed = sdf.area_fraction_below <= allowed;
    reason << 100 * sdf.area_fraction_below << "% of the surface has shape diameter below " << Mm(value)
           << " (thinnest " << Mm(sdf.min) << ", allowed " << 100 * allowed << "%)";
  }
  if (!o.passed)
    o.reason = reason.str();
  else
    o.failure.clear();
  return o;
}

// Stands on a flat surface: the centre of mass projects inside the convex
// support polygon (the lowest points, within a quarter voxel of the minimum
// z), at least `margin` mm from its boundary (Prévost et al. 2013, as cited by
// Fab Forms for its cups).
CheckOutcome Stands(const CheckSpec& spec, CheckContext& c) {
  double margin = c.Number(spec, "margin", 0.0);
  const mesh::TriangleMesh& m = c.Mesh();
  double zmin = std::numeric_limits<double>::infinity();
  for (const auto& v : m.vertices) zmin = std::min(zmin, v[2]);
  double tolerance = 0.25 * c.design().voxel_size;
  std::vector<geometry::Vec2> support;
  for (const auto& v : m.vertices)
    if (v[2] <= zmin + tolerance) support.push_back({v[0], v[1]});
  geometry::Vec3 com = c.solid().CenterOfMass();
  double inside = DistanceInsideConvexHull(support, {com[0], com[1]});
  CheckOutcome o;
  o.passed = inside >= margin;
  if (!o.passed) {
    o.failure = kUnstable;
    std::ostringstream reason;
    if (inside < 0)
      reason << "centre of mass lies " << Mm(-inside) << " outside the support polygon";
    else
      reason << "centre of mass lies only " << Mm(inside) << " inside the support polygon (margin " << Mm(margin)
             << ")";
    o.reason = reason.str();
  }
  return o;
}

CheckOutcome MaxVolume(const CheckSpec& spec, CheckContext& c) {
  double limit = c.Number(spec, "value", 0);
  double volume = c.solid().Volume();
  CheckOutcome o;
  o.passed = volume <= limit;
  if (!o.passed) {
    o.failure = kTooMuchMaterial;
    std::ostringstream reason;
    reason << "material volume " << volume << " mm^3 exceeds " << limit << " mm^3";
    o.reason = reason.str();
  }
  return o;
}

// Largest number of voxel hexahedra the fem check meshes; beyond it the sparse
// factorisation takes minutes and gigabytes (docs/benchmarks.md (FEM): 20k elements
// already take ~40 s), so the design's FEM voxel is too small.
constexpr std::size_t kMaxFemElements = 200000;

// One expression argument (an item of a list argument) evaluated with the
// sample's parameters.
double EvaluateItem(CheckContext& c, const CheckSpec& spec, const Argument& item) {
  CheckSpec one;
  one.args["item"] = item;
  one.place = spec.place;
  return c.Number(one, "item", 0);
}

// The `fixed` / `loaded` argument: exactly two [x, y, z] corners, min then max.
fem::AxisBox FemBox(CheckContext& c, const CheckSpec& spec, const std::string& name) {
  const Argument& a = spec.args.at(name);
  if (a.items.size() != 2)
    throw InputError(a.place.str() + ": check '" + spec.name + "': '" + name +
                     "' must be two corners [[xmin, ymin, zmin], [xmax, ymax, zmax]]");
  fem::AxisBox box;
  for (int k = 0; k < 3; ++k) {
    box.min[k] = EvaluateItem(c, spec, a.items[0].items[k]);
    box.max[k] = EvaluateItem(c, spec, a.items[1].items[k]);
    if (!(box.min[k] <= box.max[k]))
      throw InputError(a.place.str() + ": check '" + spec.name + "': '" + name + "' has min > max along " + "xyz"[k]);
  }
  return box;
}

// Where the FEM check clamps and loads the solid: `fixed`, `loaded` and
// `force` (N, total).
fem::FemLoadCase FemLoadCaseOf(CheckContext& c, const CheckSpec& spec) {
  fem::FemLoadCase load;
  load.fixed_region.push_back(FemBox(c, spec, "fixed"));
  load.loaded_region.push_back(FemBox(c, spec, "loaded"));
  const Argument& force = spec.args.at("force");
  for (int k = 0; k < 3; ++k) load.total_force[k] = EvaluateItem(c, spec, force.items[k]);
  return load;
}

// The FEM check's limits and element: `max_displacement` (already read as
// `limit`), `max_strain` (0: none) and `element`.
fem::FemCheckOptions FemOptionsOf(CheckContext& c, const CheckSpec& spec, double limit) {
  fem::FemCheckOptions options;
  options.max_displacement = limit;
  // `element`: incompatible_modes (default, does not lock in bending) or q1
  // (docs/fem.md).
  if (auto it = spec.args.find("element"); it != spec.args.end()) {
    if (it->second.text == "q1")
      options.solve.element = fem::StaticSolveOptions::Element::kQ1;
    else if (it->second.text != "incompatible_modes")
      throw InputError(it->second.place.str() + ": check '" + spec.name +
                       "': 'element' must be incompatible_modes or q1, got '" + it->second.text + "'");
  }
  options.max_strain = c.Number(spec, "max_strain", 0.0);
  return options;
}

// The sample's solid resampled at the FEM `voxel` (mm); an InputError naming
// `where` when that gives more than kMaxFemElements elements.
fem::VoxelSolid FemVoxels(CheckContext& c, double voxel, const std::string& where) {
  geometry::Occupancy occupancy;
  try {
    occupancy = geometry::SampleOccupancy(c.solid(), voxel, 8 * kMaxFemElements);
  } catch (const InputError& e) {
    throw InputError(where + ": " + e.what() + ": the FEM voxel is too small for the design");
  }
  if (occupancy.inside_count > kMaxFemElements) {
    std::ostringstream m;
    m << where << ": FEM voxel " << voxel << " mm gives " << occupancy.inside_count << " elements (limit "
      << kMaxFemElements << "): the FEM voxel is too small for the design";
    throw InputError(m.str());
  }
  fem::VoxelSolid voxels;
  voxels.origin = occupancy.origin;
  voxels.voxel_size = occupancy.cell_size;
  voxels.dims = occupancy.dims;
  voxels.occupied = std::move(occupancy.inside);
  return voxels;
}

// The FEM check's outcome: its reason states max displacement and strain
// against their limits whether or not it passes.
CheckOutcome FemOutcome(const fem::FemCheckResult& result, double voxel, double limit, double max_strain) {
  CheckOutcome o;
  if (result.empty_load_case) {
    // Depends on the sample's geometry (e.g. a heel height that puts the
    // sole's top between FEM node layers): the sample is invalid, the job
    // goes on.
    o.failure = kLoadCaseMissesSolid;
    std::ostringstream m;
    m << result.reason << " (" << result.num_elements << " elements of " << voxel << " mm)";
    o.reason = m.str();
    return o;
  }
  o.passed = result.passed;
  std::ostringstream reason;
  reason.precision(4);
  if (!result.passed) {
    o.failure = kTooMuchDeformation;
    if (!result.converged) reason << result.reason << "; last state: ";
  }
  reason << "max displacement " << result.max_displacement << " mm"
         << (result.max_displacement > limit ? " exceeds " : " (limit ") << limit << " mm"
         << (result.max_displacement > limit ? "" : ")") << ", max strain " << result.max_strain;
  if (max_strain > 0)
    reason << (result.max_strain > max_strain ? " exceeds " : " (limit ") << max_strain
           << (result.max_strain > max_strain ? "" : ")");
  reason << ", " << result.num_elements << " elements of " << voxel << " mm";
  o.reason = reason.str();
  o.measures["fem_max_displacement"] = result.max_displacement;
  o.measures["fem_max_strain"] = result.max_strain;
  return o;
}

// Static Neo-Hookean FEM on voxel hexahedra (Fab Forms Sec. 8, the sandal's
// deformation check; method in docs/fem.md): the solid is resampled at the
// check's own `voxel` (mm), nodes in `fixed` are clamped, `force` (N, total)
// is spread over the boundary faces inside `loaded`, and the check passes iff
// the solve converges and max |u| <= max_displacement (and the largest
// principal Green-Lagrange strain <= max_strain if given). The reason states
// max displacement and strain whether or not the check passes.
CheckOutcome Fem(const CheckSpec& spec, CheckContext& c) {
  const std::string where = spec.place.str() + ": check '" + spec.name + "'";
  const double voxel = c.Number(spec, "voxel", 0);
  if (!std::isfinite(voxel) || voxel <= 0) throw InputError(where + ": 'voxel' must be > 0 mm");
  const double youngs = c.Number(spec, "youngs_modulus", 0);
  const double poisson = c.Number(spec, "poisson", 0.3);
  const double limit = c.Number(spec, "max_displacement", 0);
  if (!std::isfinite(limit) || limit <= 0) throw InputError(where + ": 'max_displacement' must be > 0 mm");
  fem::FemLoadCase load = FemLoadCaseOf(c, spec);
  const fem::FemCheckOptions options = FemOptionsOf(c, spec, limit);
  try {
    load.material = fem::Material::FromYoungPoisson(youngs, poisson);
  } catch (const InputError& e) {
    throw InputError(where + ": " + e.what());
  }
  const fem::VoxelSolid voxels = FemVoxels(c, voxel, where);
  fem::FemCheckResult result;
  try {
    result = fem::RunFemCheck(voxels, load, options);
  } catch (const InputError& e) {
    throw InputError(where + ": " + e.what());
  }
  return FemOutcome(result, voxel, limit, options.max_strain);
}

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

// Assemblies (FabHacks, 4.3): the cycles close (pre-checks pass and C below
// the feasibility tolerance).
CheckOutcome AssemblyFeasible(CheckContext& c) {
  const auto a = c.assembly();
  const assembly::SolveSummary& s = a->summary;
  CheckOutcome o;
  o.passed = s.prechecks_passed && s.feasible;
  std::ostringstream reason;
  reason.precision(3);
  if (!o.passed) {
    o.failure = kInfeasible;
    reason << (s.messages.empty() ? std::string("the assembly does not solve") : s.messages.front());
  } else {
    reason << "feasible after " << s.starts_tried << " start" << (s.starts_tried > 1 ? "s" : "")
           << " (C = " << s.constraint_residual << " mm^2)";
  }
  o.reason = reason.str();
  return o;
}

// FabHacks, 4.3.3 step 2: nothing falls apart under gravity and the target
// part moves little during relaxation.
CheckOutcome AssemblyStable(CheckContext& c) {
  const auto a = c.assembly();
  const assembly::SolveSummary& s = a->summary;
  CheckOutcome o;
  o.passed = s.prechecks_passed && s.feasible && s.stable;
  std::ostringstream reason;
  reason.precision(3);
  if (!s.prechecks_passed || !s.feasible) {
    reason << "not solved (infeasible)";
  } else {
    reason << "relaxation moves the target " << s.relax_displacement_mm << " mm, " << s.relax_rotation_deg << " deg";
    for (std::size_t k = 0; k < s.falls_apart.size(); ++k) reason << (k ? ", " : "; falls apart: ") << s.falls_apart[k];
  }
  if (!o.passed) o.failure = kFallsApart;
  o.reason = reason.str();
  o.measures["relax_displacement"] = s.relax_displacement_mm;
  return o;
}

// The relaxed target part within `tolerance` mm (and `tolerance_deg` when the
// program matches rotation) of the end_with pose; measures target_deviation.
CheckOutcome TargetReached(const CheckSpec& spec, CheckContext& c) {
  const double tol = c.Number(spec, "tolerance", 25), tol_deg = c.Number(spec, "tolerance_deg", 10);
  const auto a = c.assembly();
  const assembly::SolveSummary& s = a->summary;
  const bool rotation = a->program.target_match_rotation;
  CheckOutcome o;
  std::ostringstream reason;
  reason.precision(4);
  if (!s.prechecks_passed || !s.feasible) {
    o.failure = kTargetMissed;
    o.reason = "not solved (infeasible)";
    return o;
  }
  o.passed = s.final_target_error_mm <= tol && (!rotation || s.final_target_error_deg <= tol_deg);
  reason << "target deviation " << s.final_target_error_mm << " mm";
  if (rotation) reason << ", " << s.final_target_error_deg << " deg";
  reason << (o.passed ? " (within " : " (exceeds ") << tol << " mm"
         << (rotation ? ", " + std::to_string(tol_deg) + " deg" : "") << ")";
  if (!o.passed) o.failure = kTargetMissed;
  o.reason = reason.str();
  o.measures["target_deviation"] = s.final_target_error_mm;
  if (rotation) o.measures["target_deviation_deg"] = s.final_target_error_deg;
  return o;
}

}  // namespace

const mesh::TriangleMesh& CheckContext::Mesh() {
  std::call_once(mesh_once_, [this] {
    mesh_ = solid_.ToMesh();
    mesh_made_ = true;
  });
  return mesh_;
}

std::shared_ptr<const mesh::TriangleMesh> CheckContext::TakeMesh() {
  if (!mesh_made_) return nullptr;
  return std::make_shared<const mesh::TriangleMesh>(std::move(mesh_));
}

double CheckContext::Number(const CheckSpec& spec, const std::string& name, double fallback) {
  auto it = spec.args.find(name);
  if (it == spec.args.end()) return fallback;
  std::lock_guard<std::mutex> lock(number_mutex_);
  return Expression(it->second.text, scope_, it->second.place).Evaluate();
}

CheckOutcome RunCheck(const CheckSpec& spec, CheckContext& context) {
  auto start = std::chrono::steady_clock::now();
  CheckOutcome o;
  if (spec.type == "watertight")
    o = Watertight(context);
  else if (spec.type == "min_thickness")
    o = MinThickness(spec, context);
  else if (spec.type == "stands")
    o = Stands(spec, context);
  else if (spec.type == "max_volume")
    o = MaxVolume(spec, context);
  else if (spec.type == "fem")
    o = Fem(spec, context);
  else if (spec.type == "collision_free")
    o = CollisionFree(spec, context);
  else if (spec.type == "assembly_feasible")
    o = AssemblyFeasible(context);
  else if (spec.type == "assembly_stable")
    o = AssemblyStable(context);
  else if (spec.type == "target_reached")
    o = TargetReached(spec, context);
  o.name = spec.name;
  o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return o;
}

namespace {
// Checks that only read the sample's solid and its surface.
bool SurfaceCheck(const CheckSpec& spec) {
  return spec.type == "watertight" || spec.type == "min_thickness" || spec.type == "stands" ||
         spec.type == "max_volume";
}
// ... and of those, the ones that read the surface mesh.
bool ReadsMesh(const CheckSpec& spec) {
  if (spec.type == "min_thickness") {
    auto it = spec.args.find("method");
    return it == spec.args.end() || it->second.text != "opening";
  }
  return spec.type == "watertight" || spec.type == "stands";
}
// ... and the ones that read the solid's measures (Solid::Volume, CenterOfMass).
bool ReadsMeasures(const CheckSpec& spec) { return spec.type == "stands" || spec.type == "max_volume"; }
}  // namespace

std::vector<CheckOutcome> RunChecks(const std::vector<CheckSpec>& specs, CheckContext& context,
                                    double* surface_seconds) {
  std::vector<CheckOutcome> outcomes(specs.size());
  std::vector<std::exception_ptr> errors(specs.size());
  if (surface_seconds) *surface_seconds = 0;
  // The solid's measures (volume, centre of mass and bbox, one pass over its
  // leaves) beside the surface extraction when a check reads them: both are
  // parallel loops over the grid, and each fills the other's idle moments.
  tbb::task_group measures;
  if (std::any_of(specs.begin(), specs.end(), ReadsMeasures)) measures.run([&context] { context.solid().Volume(); });
  if (std::any_of(specs.begin(), specs.end(), ReadsMesh)) {
    auto start = std::chrono::steady_clock::now();
    context.Mesh();
    if (surface_seconds)
      *surface_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  measures.wait();
  tbb::task_group group;
  for (std::size_t i = 0; i < specs.size(); ++i)
    if (SurfaceCheck(specs[i]))
      group.run([&, i] {
        try {
          outcomes[i] = RunCheck(specs[i], context);
        } catch (...) {
          errors[i] = std::current_exception();
        }
      });
  group.wait();
  for (std::size_t i = 0; i < specs.size(); ++i) {
    if (errors[i]) std::rethrow_exception(errors[i]);  // the first in the design's order
    if (!SurfaceCheck(specs[i])) outcomes[i] = RunCheck(specs[i], context);
  }
  return outcomes;
}

double DistanceInsideConvexHull(std::vector<geometry::Vec2> pts, const geometry::Vec2& p) {
  const std::vector<geometry::Vec2> hull = ConvexHull2D(std::move(pts));  // counter-clockwise
  if (hull.size() < 3) return -std::numeric_limits<double>::infinity();
  // Inside: distance to the nearest edge line; outside: distance to the hull.
  bool inside = true;
  double nearest_line = std::numeric_limits<double>::infinity();
  double nearest_segment = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const auto& a = hull[i];
    const auto& b = hull[(i + 1) % hull.size()];
    double ex = b[0] - a[0], ey = b[1] - a[1], len = std::hypot(ex, ey);
    double side = Cross(a, b, p) / len;
    if (side < 0) inside = false;
    nearest_line = std::min(nearest_line, side);
    double t = std::clamp(((p[0] - a[0]) * ex + (p[1] - a[1]) * ey) / (len * len), 0.0, 1.0);
    nearest_segment = std::min(nearest_segment, std::hypot(p[0] - a[0] - t * ex, p[1] - a[1] - t * ey));
  }
  return inside ? nearest_line : -nearest_segment;
}

std::vector<std::string> RepairParameters(const Design& design) {
  std::vector<std::string> out;
  for (const CheckSpec& spec : design.checks) {
    if (spec.type != "collision_free") continue;
    const auto it = spec.args.find("repair_with");
    if (it == spec.args.end()) continue;
    std::string name;
    for (const char c : it->second.text + ",") {
      if (c == ',' || c == ' ') {
        if (!name.empty()) out.push_back(name);
        name.clear();
      } else {
        name += c;
      }
    }
  }
  return out;
}

}  // namespace fabatlas::design
