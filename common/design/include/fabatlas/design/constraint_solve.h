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
  // true: decide first from the constraints that define a variable outright
  // (below), and run Ceres only for what they leave undecided. false: Ceres
  // always (the reference the definitions are tested against).
  bool use_definitions = true;
  // The definitions call a point unsatisfiable only when a bound or a
  // constraint misses by more than this factor times the first-order bound
  // on how far the tolerance lets a solution move (below).
  double definition_safety = 10;
};

struct ConstraintSolveSummary {
  bool satisfiable = false;
  // Every parameter's value, exposed (as given) and mutable (as solved).
  std::map<std::string, double> values;
  double max_violation = 0;      // largest constraint violation at the solution
  std::string worst_constraint;  // the text of the most violated constraint
  double seconds = 0;
  bool by_definitions = false;  // decided from the definitions, without Ceres
};

// Fixes the exposed parameters at u and solves for the mutable ones.
//
// Definitions first (ConstraintSolveOptions::use_definitions): a constraint
// `v == expression` (either side) whose one side is a bare variable v the
// other side does not read defines v outright once the names the expression
// reads are known. Following definitions from the exposed values gives the
// only candidate x* for every variable they reach; any solution lies within
// e_v of x*_v, with e_v = tolerance + sum_j |d expression / d x_j| e_j (first
// order, central differences). The point is then
// - unsatisfiable (no Ceres run) when some x*_v lies outside v's bounds by
//   more than definition_safety * e_v, or a constraint all of whose names
//   are reached misses at x* by more than definition_safety times its own
//   first-order bound (tolerance + sum_j |d(lhs - rhs) / d x_j| e_j); the
//   reported violation is measured with x* clamped into the bounds;
// - satisfiable at x* (no Ceres run) when the definitions reach every
//   variable, x* is within the bounds and every constraint holds there;
// - otherwise left to Ceres (a variable no definition reaches, a miss within
//   the margin, a non-finite value).
// Holey vase: every one of its 6 variables is defined, so each sample is
// decided without Ceres.
//
// Ceres: phase 1 minimises constraint residuals plus a small least-change term
// (stay near the designer's defaults) within the variables' bounds; phase 2
// polishes the constraint residuals alone from there. The design is
// unsatisfiable at u when the largest violation stays above the tolerance.
// Thread-safe (no shared state).
ConstraintSolveSummary SolveConstraints(const Design& design, const Point& u,
                                        const ConstraintSolveOptions& options = {});

}  // namespace fabatlas::design
