// Newton iterations of a static solve (static_solve/newton.h).
#include "newton.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "fabatlas/stopwatch.h"

namespace fabatlas::fem::internal {

double Potential(const Equilibrium& eq, const Eigen::VectorXd& u, const Eigen::VectorXd& alpha, double lambda) {
  return eq.problem.StrainEnergy(u, alpha) - lambda * eq.f_total.dot(u);
}

bool SolveIncrement(const Equilibrium& eq, double target, const Eigen::VectorXd& u0, const Eigen::VectorXd& alpha0,
                    Eigen::VectorXd& u, Eigen::VectorXd& alpha, StaticSolveSummary& summary, std::string& failure) {
  const StaticSolveOptions& options = eq.options;
  eq.dofs.Prescribe(target, u);
  bool step_ok = false;
  double scale = target * eq.f_total_free.norm();
  for (int attempt = options.full_newton_first ? 0 : 1; attempt < 2 && !step_ok; ++attempt) {
    const bool line_search = attempt == 1;
    if (attempt == 1 && options.full_newton_first) {
      u = u0;
      alpha = alpha0;
      eq.dofs.Prescribe(target, u);
      if (options.verbose) std::fprintf(stderr, "fem: full Newton steps failed (%s); line search\n", failure.c_str());
      failure.clear();
    }
    step_ok = NewtonIterations(eq, target, line_search, u, alpha, scale, summary, failure);
  }
  return step_ok;
}

bool NewtonIterations(const Equilibrium& eq, double target, bool line_search, Eigen::VectorXd& u,
                      Eigen::VectorXd& alpha, double& scale, StaticSolveSummary& summary, std::string& failure) {
  const StaticSolveOptions& options = eq.options;
  Problem& problem = eq.problem;
  Eigen::VectorXd f_int, f_cond, dalpha, d_full(u.size());
  for (int it = 0; it < options.max_newton_iterations; ++it) {
    const Stopwatch assembly_time;
    const double ra2 = problem.Assemble(u, alpha, &f_int, &f_cond, true);
    summary.assembly_seconds += assembly_time.Seconds();
    // The gradient of Pi: r_u (free DOFs) and r_alpha; the Newton system
    // uses the condensed r (static condensation, Problem).
    const Eigen::VectorXd r_u = eq.dofs.Restrict(f_int) - target * eq.f_total_free;
    const Eigen::VectorXd r =
        eq.incompatible ? Eigen::VectorXd(eq.dofs.Restrict(f_cond) - target * eq.f_total_free) : r_u;
    const double rnorm = std::sqrt(r_u.squaredNorm() + ra2);
    if (!std::isfinite(rnorm)) {
      failure = "non-finite residual (inverted element)";
      return false;
    }
    if (it == 0) scale = std::max(scale, rnorm);
    summary.final_residual_norm = rnorm;
    if (options.verbose) {
      std::fprintf(stderr, "fem: lambda=%.4f it=%d |r|=%.3e scale=%.3e\n", target, it, rnorm, scale);
    }
    if (rnorm <= options.relative_tolerance * scale || scale == 0.0) return true;
    // Newton direction: K d = -r, K shifted until positive definite.
    Eigen::VectorXd d;
    double shift = 0;
    if (!eq.tangent.Solve(problem.K(), problem.diagonal_slots(), eq.dofs.num_free, r, d, shift, summary)) {
      failure = eq.tangent.Failure();
      return false;
    }
    ++summary.newton_iterations;
    // The full step: d on the free DOFs (d_full on all DOFs) and the mode
    // increments it implies (static condensation).
    eq.dofs.Spread(d, d_full);
    const double slope_alpha = problem.AlphaIncrement(d_full, &dalpha);
    const double slope = r_u.dot(d) + slope_alpha;  // dPi/dstep at step = 0 (< 0)
    double step = 1.0;
    if (!LineSearch(eq, target, line_search, rnorm, slope, d_full, dalpha, u, alpha, step)) {
      failure = "line search found no decrease of the energy";
      return false;
    }
    if (options.verbose) {
      std::fprintf(stderr, "fem:   step %.3g shift=%.3g |d|=%.3e\n", step, shift, d.norm());
    }
    // Rounding floor: a full Newton step that moves no node by more than
    // step_tolerance relative to the displacement field is converged.
    if (step == 1.0 && d.lpNorm<Eigen::Infinity>() <= options.step_tolerance * u.lpNorm<Eigen::Infinity>()) {
      return true;
    }
  }
  return false;
}

}  // namespace fabatlas::fem::internal
