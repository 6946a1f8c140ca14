// The backtracking line search of a static solve's Newton iterations
// (static_solve/newton.h): Armijo's condition on the potential energy.
#include <cmath>

#include "newton.h"

namespace fabatlas::fem::internal {

bool LineSearch(const Equilibrium& eq, double target, bool line_search, double rnorm, double slope,
                const Eigen::VectorXd& d_full, const Eigen::VectorXd& dalpha, Eigen::VectorXd& u,
                Eigen::VectorXd& alpha, double& step) {
  const StaticSolveOptions& options = eq.options;
  Eigen::VectorXd u_trial = u, alpha_trial = alpha;
  // Full Newton steps only need the trial's energy to be finite (no
  // inverted element), not the energy here.
  const double pi0 = line_search ? Potential(eq, u, alpha, target) : 0.0;
  step = 1.0;
  bool accepted = false;
  for (int ls = 0; ls <= options.max_line_search_halvings; ++ls, step *= 0.5) {
    u_trial = u + step * d_full;
    alpha_trial = alpha + step * dalpha;
    const double pi = Potential(eq, u_trial, alpha_trial, target);
    if (!std::isfinite(pi)) continue;
    if (!line_search || pi <= pi0 + options.armijo_c * step * slope) {
      accepted = true;
      break;
    }
    // Near the solution the energy decrease (~ r.d/2) drops below the
    // rounding noise of the energy sum; then accept a step that reduces
    // the residual norm instead.
    if (std::isfinite(pi0) && std::abs(pi - pi0) <= eq.energy_noise) {
      Eigen::VectorXd f_trial;
      const double ra2_trial = eq.problem.Assemble(u_trial, alpha_trial, &f_trial, nullptr, false);
      const Eigen::VectorXd r_trial = eq.dofs.Restrict(f_trial) - target * eq.f_total_free;
      if (std::sqrt(r_trial.squaredNorm() + ra2_trial) < rnorm) {
        accepted = true;
        break;
      }
    }
  }
  if (!accepted) return false;
  u = u_trial;
  alpha = alpha_trial;
  return true;
}

}  // namespace fabatlas::fem::internal
