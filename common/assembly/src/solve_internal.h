// Internals of the two-step solve exposed for tests (not installed).
#pragma once

#include "fabatlas/assembly/program.h"
#include "fabatlas/assembly/solve.h"

namespace fabatlas::assembly::internal {

// The solve's analytic Jacobian (forward kinematics, see solve.cc) against
// Ceres autodiff of the same residuals, at the connection parameters of start
// `start` (0 = box centre, else Halton), for one phase (0 feasibility,
// 1 objective with σ = penalty_start, 2 relaxation with σ_r).
struct JacobianCheck {
  int residuals = 0, parameters = 0;
  double max_error = 0;  // largest |analytic − autodiff| entry
  double max_entry = 0;  // largest |autodiff| entry
  double max_residual_error = 0;
};
JacobianCheck CheckJacobian(const Program& program, int start, int phase, const SolveOptions& options = {});

// SolveAssembly with every free connection parameter of the step-1 solution
// moved by `delta` (degrees for angles, the parameter's own unit otherwise;
// clamped to its bounds) before the relaxation: a converged relaxation must
// not depend on it beyond the solver tolerances.
SolveSummary SolvePerturbedRelaxation(const Program& program, double delta, const SolveOptions& options = {});

}  // namespace fabatlas::assembly::internal
