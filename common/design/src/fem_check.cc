// The fem check: the sample voxelised and loaded as the design says, solved
// by fem::RunFemCheck (docs/fem.md).

#include <cmath>
#include <sstream>

#include "check_kinds.h"
#include "checks.h"
#include "fabatlas/error.h"
#include "fabatlas/fem/fem_check.h"

namespace fabatlas::design {
namespace {

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

}  // namespace

namespace check {

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

}  // namespace check

}  // namespace fabatlas::design
