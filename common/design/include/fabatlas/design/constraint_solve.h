// fabatlas/design/constraint_solve.h — resolve mutable parameters for a point
// (Fab Forms Alg. 2, lines 1–3: "fix exposed parameters at u; run constraint
// solver").
#pragma once

#include <map>
#include <string>

#include "fabatlas/design/design.h"

namespace fabatlas::design {

struct ConstraintSolveOptions {
  // A constraint counts as satisfied when its violation (|lhs - rhs| for ==,
  // the overshoot for <= and >=) is at most this, in the constraint's units.
  double tolerance = 1e-6;
  // Weight of the least-change term sum (m_i - default_i)^2 relative to the
  // constraint residuals in the first phase. Small: constraints dominate.
  double least_change_weight = 1e-3;
  int max_iterations = 200;
};

struct ConstraintSolveSummary {
  bool satisfiable = false;
  // Every parameter's value, exposed (as given) and mutable (as solved).
  std::map<std::string, double> values;
  double max_violation = 0;   // largest constraint violation at the solution
  std::string worst_constraint;  // the text of the most violated constraint
  double seconds = 0;
};

// Fixes the exposed parameters at u and solves for the mutable ones with
// Ceres: phase 1 minimises constraint residuals plus a small least-change term
// (stay near the designer's defaults) within the variables' bounds; phase 2
// polishes the constraint residuals alone from there. The design is
// unsatisfiable at u when the largest violation stays above the tolerance.
// Thread-safe (no shared state).
ConstraintSolveSummary SolveConstraints(const Design& design, const Point& u,
                                        const ConstraintSolveOptions& options = {});

}  // namespace fabatlas::design
