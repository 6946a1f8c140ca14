// Total Lagrangian Q1 hexahedra, Neo-Hookean, Newton + line search + load
// stepping. See static_solve.h for the method and docs/fem.md. The parts
// live in src/static_solve/: Gauss points (gauss_points.*), the discrete
// problem and its assembly (problem.*), the unknowns and the load
// (dof_map.*), the shifted tangent solve (tangent_solve.*), the Newton
// iterations of one load increment (newton.*) and their line search
// (line_search.cc). This file checks the input and steps the load.
#include "fabatlas/fem/static_solve.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "fabatlas/error.h"
#include "fabatlas/stopwatch.h"
#include "static_solve/dof_map.h"
#include "static_solve/gauss_points.h"
#include "static_solve/newton.h"
#include "static_solve/problem.h"
#include "static_solve/tangent_solve.h"

namespace fabatlas::fem {

void BoundaryConditions::FixNode(int node) {
  for (int c = 0; c < 3; ++c) dirichlet.push_back({node, c, 0.0});
}

void BoundaryConditions::FixComponentEverywhere(const HexMesh& mesh, int component) {
  for (int n = 0; n < static_cast<int>(mesh.nodes.size()); ++n) {
    dirichlet.push_back({n, component, 0.0});
  }
}

namespace {

// Throws InputError for an empty mesh, a material or load-step count out of
// range, or an element naming a node that does not exist.
void CheckInput(const HexMesh& mesh, const Material& material, const StaticSolveOptions& options) {
  if (mesh.elements.empty()) throw InputError("static solve: mesh has no elements");
  if (!(material.mu > 0) || !(material.kappa > 0)) {
    throw InputError("static solve: material needs mu > 0 and kappa > 0");
  }
  if (options.load_steps < 1) throw InputError("static solve: load_steps must be >= 1");
  const int nn = static_cast<int>(mesh.nodes.size());
  for (const auto& el : mesh.elements)
    for (int a : el)
      if (a < 0 || a >= nn) throw InputError("hex mesh: element node index " + std::to_string(a) + " out of range");
}

// The load factor from 0 to 1 in increments of 1 / load_steps; an increment
// that fails is redone from its start at half the size (at most
// max_cutbacks times), and after two quick increments in a row a cut-back
// increment grows again (doubling, up to 1 / load_steps).
void StepTheLoad(const internal::Equilibrium& eq, Eigen::VectorXd& u, Eigen::VectorXd& alpha,
                 StaticSolveSummary& summary) {
  const StaticSolveOptions& options = eq.options;
  double lambda = 0.0;
  double dlambda = 1.0 / options.load_steps;
  int cutbacks = 0;
  int easy_steps = 0;  // consecutive steps that converged quickly
  while (lambda < 1.0 - 1e-14) {
    const double target = std::min(1.0, lambda + dlambda);
    const Eigen::VectorXd u_step_start = u;
    const Eigen::VectorXd alpha_step_start = alpha;
    const int iterations_before = summary.newton_iterations;
    std::string failure;
    if (internal::SolveIncrement(eq, target, u_step_start, alpha_step_start, u, alpha, summary, failure)) {
      lambda = target;
      ++summary.load_steps_taken;
      easy_steps = summary.newton_iterations - iterations_before <= options.quick_step_iterations ? easy_steps + 1 : 0;
      if (easy_steps >= 2 && dlambda < 1.0 / options.load_steps) {
        dlambda = std::min(2 * dlambda, 1.0 / options.load_steps);
        easy_steps = 0;
      }
      continue;
    }
    easy_steps = 0;
    u = u_step_start;
    alpha = alpha_step_start;
    if (failure.empty()) {
      failure = "no convergence in " + std::to_string(options.max_newton_iterations) + " Newton iterations";
    }
    if (cutbacks >= options.max_cutbacks) {
      summary.message =
          failure + " at load factor " + std::to_string(target) + " after " + std::to_string(cutbacks) + " cutbacks";
      break;
    }
    ++cutbacks;
    dlambda *= 0.5;
  }
  summary.converged = lambda >= 1.0 - 1e-14;
  if (!summary.converged && summary.message.empty()) summary.message = "did not reach the full load";
}

}  // namespace

StaticSolveSummary SolveStatic(const HexMesh& mesh, const Material& material, const BoundaryConditions& bc,
                               const StaticSolveOptions& options) {
  const Stopwatch total_time;
  StaticSolveSummary summary;
  CheckInput(mesh, material, options);
  const int nn = static_cast<int>(mesh.nodes.size());
  const internal::DofMap dofs = internal::NumberDofs(mesh, bc);
  const Eigen::VectorXd f_total = internal::TotalLoad(mesh, bc);

  std::vector<internal::GaussPoint> gauss_points = internal::PrecomputeGaussPoints(mesh);
  // Rounding noise of the energy sum: a few ulps of the energy density
  // scale (mu + kappa) times the reference volume.
  double volume = 0;
  for (const auto& gp : gauss_points) volume += gp.weight;
  const double energy_noise = 1e-11 * (material.mu + material.kappa) * volume;
  const bool incompatible = options.element == StaticSolveOptions::Element::kIncompatibleModes;
  internal::Problem problem(mesh, material, std::move(gauss_points), dofs.free_index, dofs.coefficient, dofs.num_free,
                            incompatible);
  summary.num_free_dofs = dofs.num_free;
  const Eigen::VectorXd f_total_free = dofs.Restrict(f_total);
  internal::TangentSolve tangent(options);
  const internal::Equilibrium eq{problem, dofs, f_total, f_total_free, energy_noise, incompatible, options, tangent};

  Eigen::VectorXd u = Eigen::VectorXd::Zero(3 * static_cast<Eigen::Index>(nn));
  Eigen::VectorXd alpha = Eigen::VectorXd::Zero(problem.num_alpha());  // incompatible modes, mm
  StepTheLoad(eq, u, alpha, summary);

  summary.displacements.resize(static_cast<std::size_t>(nn));
  for (int n = 0; n < nn; ++n) {
    Vec3 d{u[3 * n], u[3 * n + 1], u[3 * n + 2]};
    summary.displacements[n] = d;
    summary.max_displacement = std::max(summary.max_displacement, std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
  }
  summary.max_principal_strain = problem.MaxPrincipalStrain(u, alpha);
  summary.total_seconds = total_time.Seconds();
  return summary;
}

}  // namespace fabatlas::fem
