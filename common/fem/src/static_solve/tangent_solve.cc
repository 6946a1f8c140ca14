// The shifted tangent solve of a static solve (static_solve/tangent_solve.h).
#include "tangent_solve.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "fabatlas/stopwatch.h"

namespace fabatlas::fem::internal {

TangentSolve::TangentSolve(const StaticSolveOptions& options)
    : options_(options), direct_(options.linear_solver == StaticSolveOptions::LinearSolver::kCholesky) {
#ifdef FABATLAS_FEM_HAVE_CHOLMOD
  cholesky_.cholmod().print = 0;  // the shift handles "not positive definite"
  // Orderings: the unknowns' own (nested dissection, dof_map.h) or AMD, the
  // better of the two by CHOLMOD's analysis of both (fill and flops). Never
  // METIS or NESDIS, CHOLMOD's default candidates: METIS draws from the
  // process's one rand() generator, so its permutation changed with other
  // threads' draws (nested_dissection.h).
  cholesky_.cholmod().nmethods = 2;
  cholesky_.cholmod().method[0].ordering = CHOLMOD_NATURAL;
  cholesky_.cholmod().method[1].ordering = CHOLMOD_AMD;
#endif
  cg_ic_.setTolerance(options.cg_relative_tolerance);
  cg_ic_.setMaxIterations(options.cg_max_iterations);
  cg_jacobi_.setTolerance(options.cg_relative_tolerance);
  cg_jacobi_.setMaxIterations(options.cg_max_iterations);
}

void TangentSolve::Analyse(const SpMat& K) {
  cholesky_.analyzePattern(K);
  analysed_ = true;
#ifdef FABATLAS_FEM_HAVE_CHOLMOD
  if (options_.verbose) {
    const cholmod_common& c = cholesky_.cholmod();
    std::fprintf(stderr, "fem: ordering %s, factor entries %.4g, flops %.4g\n",
                 c.method[c.selected].ordering == CHOLMOD_AMD ? "AMD" : "nested dissection", c.lnz, c.fl);
  }
#endif
}

bool TangentSolve::TrySolve(const SpMat& K, const Eigen::VectorXd& r, Eigen::VectorXd& d, StaticSolveSummary& summary) {
  ++summary.factorizations;
  if (direct_) {
    cholesky_.factorize(K);
    if (cholesky_.info() != Eigen::Success) return false;
    d = cholesky_.solve(-r);
    return true;
  }
  bool ok = false;
  if (options_.linear_solver == StaticSolveOptions::LinearSolver::kConjugateGradientJacobi) {
    cg_jacobi_.compute(K);
    d = cg_jacobi_.solve(-r);
    summary.linear_iterations += cg_jacobi_.iterations();
    ok = cg_jacobi_.info() == Eigen::Success;
  } else {
    cg_ic_.compute(K);
    if (cg_ic_.preconditioner().info() != Eigen::Success) return false;
    d = cg_ic_.solve(-r);
    summary.linear_iterations += cg_ic_.iterations();
    ok = cg_ic_.info() == Eigen::Success;
  }
  return ok && d.allFinite() && r.dot(d) < 0;
}

bool TangentSolve::Solve(SpMat& K, const std::vector<int>& diagonal, int num_free, const Eigen::VectorXd& r,
                         Eigen::VectorXd& d, double& shift, StaticSolveSummary& summary) {
  const Stopwatch solve_time;
  if (!analysed_ && direct_) Analyse(K);
  double mean_diag = 0;
  for (int j = 0; j < num_free; ++j) mean_diag += std::abs(K.valuePtr()[diagonal[j]]);
  mean_diag /= num_free;
  shift = 0;
  // Shifts: the first try uses a tenth of the last shift that worked
  // (none once that falls below 1e-6 x the mean diagonal, and none if
  // the last step needed none): the tangent changes little between
  // iterations, and every failed try is a factorisation. Then 1e-6 x the
  // mean diagonal or the last shift, times 10 each try.
  double first = 0.1 * last_shift_ratio_ >= 1e-6 ? 0.1 * last_shift_ratio_ * mean_diag : 0.0;
  if (first > 0) {
    for (int j = 0; j < num_free; ++j) K.valuePtr()[diagonal[j]] += first;
    shift = first;
  }
  bool solved = TrySolve(K, r, d, summary);
  while (!solved && shift < 1e6 * mean_diag) {
    const double next = shift == 0 ? std::max(1e-6, 0.1 * last_shift_ratio_) * mean_diag : shift * 10;
    for (int j = 0; j < num_free; ++j) K.valuePtr()[diagonal[j]] += next - shift;
    shift = next;
    solved = TrySolve(K, r, d, summary);
  }
  last_shift_ratio_ = shift / mean_diag;
  summary.linear_solve_seconds += solve_time.Seconds();
  return solved;
}

const char* TangentSolve::Failure() const {
  return direct_ ? "tangent stiffness could not be factorised (a part not held by the fixed region?)"
                 : "conjugate gradients did not converge on the tangent stiffness (a part not held by "
                   "the fixed region?)";
}

}  // namespace fabatlas::fem::internal
