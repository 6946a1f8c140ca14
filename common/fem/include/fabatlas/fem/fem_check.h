// fabatlas/fem/fem_check.h — the design-level FEM validity check.
//
// Fab Forms (Sec. 8) validates its sandal design by a static finite-element
// analysis: the solid is voxelised into hexahedra, a region is fixed, a load
// is applied to another region, and the sample is invalid if the deformation
// exceeds a threshold (docs/fem.md). This header runs that check on
// a VoxelSolid with static_solve.h.
#pragma once

#include <string>
#include <vector>

#include "fabatlas/fem/hex_mesh.h"
#include "fabatlas/fem/neo_hookean.h"
#include "fabatlas/fem/static_solve.h"

namespace fabatlas::fem {

struct AxisBox {
  Vec3 min{0, 0, 0};  // mm
  Vec3 max{0, 0, 0};  // mm
  bool Contains(const Vec3& p, double tolerance = 0.0) const;
};

struct FemLoadCase {
  // Every mesh node inside any of these boxes (closed, with a tolerance of
  // 1e-6 voxel) is fixed in all three components.
  std::vector<AxisBox> fixed_region;
  // The total force is spread as a uniform dead traction over the boundary
  // faces whose four nodes all lie inside one of these boxes.
  std::vector<AxisBox> loaded_region;
  Vec3 total_force{0, 0, 0};  // N
  Material material;          // MPa (see Material::FromYoungPoisson)
};

struct FemCheckOptions {
  double max_displacement = 1.0;  // mm; the check fails above it
  double max_strain = 0.0;        // principal Green-Lagrange; <= 0: not checked
  // Solver settings. The check starts with a single load step: valid designs
  // deform little, and a step that fails is halved (max_cutbacks), so hard
  // cases still get load stepping. On the 20k-element heel of bench/fem this
  // takes 5 Newton iterations instead of 16 with 4 steps (same answer).
  StaticSolveOptions solve{.load_steps = 1};
};

struct FemCheckResult {
  bool passed = false;
  bool converged = false;
  double max_displacement = 0;  // mm
  double max_strain = 0;        // largest |principal Green-Lagrange strain|
  // The load case selects nothing on this solid: no occupied voxel, a fixed
  // region with no node, or a loaded region with no boundary face (reason
  // says which). No solve is run and passed is false. For a parametric
  // design this depends on the sample's geometry, so it is a verdict on
  // the sample, not an input error.
  bool empty_load_case = false;
  int num_elements = 0;
  int newton_iterations = 0;
  double seconds = 0;               // wall time of the whole check
  double assembly_seconds = 0;      // of which element assembly
  double linear_solve_seconds = 0;  // of which sparse factorisation + solves
  long long linear_iterations = 0;  // conjugate-gradient iterations (iterative solvers only)
  std::string reason;               // one line when !passed, empty otherwise
};

// Meshes the solid (HexMeshFromVoxels), applies the load case and solves.
// passed = converged && max_displacement <= options.max_displacement (&& the
// strain limit if set). An empty solid, a fixed region that selects no node
// or a loaded region that selects no boundary face fail the check with
// empty_load_case set (see FemCheckResult). Throws InputError for a bad
// voxel grid or material.
FemCheckResult RunFemCheck(const VoxelSolid& solid, const FemLoadCase& load, const FemCheckOptions& options = {});

}  // namespace fabatlas::fem
