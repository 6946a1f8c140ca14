// static_solve/newton.h (internal to fabatlas_fem) — equilibrium at one load
// factor: Newton iterations on the potential energy Pi(u, alpha) =
// W(u, alpha) - lambda f . u (newton.cc) with the shifted tangent solve
// (tangent_solve.h) and a backtracking line search (line_search.cc).
#pragma once

#include <string>

#include <Eigen/Core>

#include "dof_map.h"
#include "fabatlas/fem/static_solve.h"
#include "problem.h"
#include "tangent_solve.h"

namespace fabatlas::fem::internal {

// What the Newton iterations of every load increment share.
struct Equilibrium {
  Problem& problem;
  const DofMap& dofs;
  const Eigen::VectorXd& f_total;       // full load on every mesh DOF (N)
  const Eigen::VectorXd& f_total_free;  // its restriction to the unknowns
  double energy_noise;                  // rounding noise of the energy sum (mJ)
  bool incompatible;                    // incompatible-mode elements (condensed)
  const StaticSolveOptions& options;
  TangentSolve& tangent;
};

// Pi(u, alpha) at load factor lambda (mJ); +inf if an element inverts.
double Potential(const Equilibrium& eq, const Eigen::VectorXd& u, const Eigen::VectorXd& alpha, double lambda);

// One load increment to load factor `target` from the state (u0, alpha0) at
// its start, solved in place in (u, alpha): full Newton steps first when
// options.full_newton_first (halved only while an element would invert);
// if they do not converge, again from the start with the Armijo line
// search. True when converged; otherwise `failure` says why (empty: the
// iteration cap).
bool SolveIncrement(const Equilibrium& eq, double target, const Eigen::VectorXd& u0, const Eigen::VectorXd& alpha0,
                    Eigen::VectorXd& u, Eigen::VectorXd& alpha, StaticSolveSummary& summary, std::string& failure);

// Newton iterations at load factor `target` from (u, alpha), in place, with
// the line search when `line_search` (else full steps). `scale` is the
// residual scale of the convergence test (the first residual raises it).
bool NewtonIterations(const Equilibrium& eq, double target, bool line_search, Eigen::VectorXd& u,
                      Eigen::VectorXd& alpha, double& scale, StaticSolveSummary& summary, std::string& failure);

// Steps along (d_full, dalpha) from (u, alpha), halving from 1: with
// `line_search`, the first step that satisfies Armijo's condition on Pi
// with the initial slope `slope` (< 0), or that lowers the residual norm
// below `rnorm` when Pi's change is below its rounding noise; without it,
// the first step with a finite Pi. Moves (u, alpha) and sets `step` when
// one is found; false otherwise.
bool LineSearch(const Equilibrium& eq, double target, bool line_search, double rnorm, double slope,
                const Eigen::VectorXd& d_full, const Eigen::VectorXd& dalpha, Eigen::VectorXd& u,
                Eigen::VectorXd& alpha, double& step);

}  // namespace fabatlas::fem::internal
