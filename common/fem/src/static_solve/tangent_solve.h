// static_solve/tangent_solve.h (internal to fabatlas_fem) — the Newton
// direction of a static solve: K d = -r with the tangent K shifted on its
// diagonal until positive definite, by sparse Cholesky (CHOLMOD when built
// with it, else Eigen's SimplicialLLT) or conjugate gradients
// (StaticSolveOptions::linear_solver). One per solve: it keeps the
// symbolic analysis and the last shift that worked.
#pragma once

#include <vector>

#include <Eigen/Core>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Sparse>
#ifdef FABATLAS_FEM_HAVE_CHOLMOD
#include <Eigen/CholmodSupport>
#endif

#include "fabatlas/fem/static_solve.h"
#include "problem.h"

namespace fabatlas::fem::internal {

#ifdef FABATLAS_FEM_HAVE_CHOLMOD
using Cholesky = Eigen::CholmodSupernodalLLT<SpMat, Eigen::Lower>;
#else
using Cholesky = Eigen::SimplicialLLT<SpMat, Eigen::Lower, Eigen::AMDOrdering<int>>;
#endif

class TangentSolve {
 public:
  explicit TangentSolve(const StaticSolveOptions& options);

  // d with K d = -r, K (its diagonal slots `diagonal`, num_free unknowns)
  // shifted until positive definite; `shift` is the shift used. Counts
  // factorisations, CG iterations and the time in summary. False when no
  // shift up to 1e6 x the mean diagonal works (then Failure() says why).
  bool Solve(SpMat& K, const std::vector<int>& diagonal, int num_free, const Eigen::VectorXd& r, Eigen::VectorXd& d,
             double& shift, StaticSolveSummary& summary);
  // One line: why Solve failed.
  const char* Failure() const;

 private:
  // One attempt at K d = -r with K as it is; false if K is not
  // (numerically) positive definite or the solve did not converge.
  bool TrySolve(const SpMat& K, const Eigen::VectorXd& r, Eigen::VectorXd& d, StaticSolveSummary& summary);
  void Analyse(const SpMat& K);

  const StaticSolveOptions& options_;
  const bool direct_;
  Cholesky cholesky_;
  // Iterative alternatives (static_solve.h): K is stored in full, so both
  // triangles are used in the products.
  Eigen::ConjugateGradient<SpMat, Eigen::Lower | Eigen::Upper,
                           Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>>>
      cg_ic_;
  Eigen::ConjugateGradient<SpMat, Eigen::Lower | Eigen::Upper, Eigen::DiagonalPreconditioner<double>> cg_jacobi_;
  bool analysed_ = false;
  double last_shift_ratio_ = 0;  // last diagonal shift / mean diagonal
};

}  // namespace fabatlas::fem::internal
