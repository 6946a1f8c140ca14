// The two-step assembly solve of FabHacks (Mei et al., "FabHacks: Transform
// Everyday Objects into Home Hacks Leveraging a Solver-aided DSL", SCF '24,
// Sec. 4.3; docs/references.md): pre-checks, then step 1 (close the cycles from
// several starts, then the target objective with a doubling penalty) and
// step 2 (relax under gravity, with static friction along rods and an
// active set of parameters at their bounds), then what falls apart.
//
// The parts live in src/solve/: reduced-coordinate kinematics
// (kinematics.h), the target (target_form.*), the residuals
// (assembly_residual.h) and their analytic Jacobian (assembly_cost.*), the
// gauge anchor and stopping rules, and the Solver (solver.h) with its start
// points, runs, friction and active set, one file each; resting contacts in
// resting_contacts.*. This file drives them.
#include "fabatlas/assembly/solve.h"

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "fabatlas/assembly/precheck.h"
#include "fabatlas/stopwatch.h"
#include "solve/resting_contacts.h"
#include "solve/solver.h"
#include "solve/target_form.h"
#include "solve_internal.h"

namespace fabatlas::assembly {
namespace {

using internal::Block;
using internal::Phase;
using internal::Solver;
using internal::TargetForm;

void TargetErrors(const Program& prog, const Eigen::Isometry3d& pose, double& mm, double& deg) {
  TargetForm::Of(prog).Errors(pose.matrix(), mm, deg);
}

// Relaxation runs after which the active set is no longer updated (each
// update pins or unpins at least one parameter; a guard against cycling).
constexpr int kMaxRelaxationRuns = 400;
constexpr int kActiveSetRound = 1000;  // iterations per round of an active-set relaxation

// Step 1 (FabHacks Sec. 4.3.3) over the starts: close the cycles, then
// minimise the target objective with the penalty σ doubling; keeps the
// best. False when no start closes the cycles (the parameters are then
// those of the start that came closest).
bool Step1(const Program& prog, const SolveOptions& opt, Solver& solver, SolveSummary& out) {
  std::vector<Block> best;
  double best_obj = std::numeric_limits<double>::infinity();
  int objective_starts = 0;
  std::vector<Block> closest;  // infeasible: the start that came closest to closing
  double closest_c = std::numeric_limits<double>::infinity();
  for (int k = 0; k < opt.restarts; ++k) {
    ++out.starts_tried;
    const Stopwatch feasibility_time;
    if (k == opt.chain_start && solver.ClosesCycles())
      solver.SetChainStart();
    else
      solver.SetStart(k);
    if (solver.ConstraintResidual() >= opt.feasibility_tolerance) solver.Run(Phase::kFeasibility, 1.0);
    const double c = solver.ConstraintResidual();
    out.feasibility_seconds += feasibility_time.Seconds();
    if (c >= opt.feasibility_tolerance) {
      if (c < closest_c) closest_c = c, closest = solver.blocks();
      continue;
    }
    if (!out.feasible) out.feasibility_starts = k + 1;
    out.feasible = true;
    const Stopwatch objective_time;
    // Step 1: user objective with penalty σ doubling (FabHacks, 4.3.3).
    double sigma = opt.penalty_start;
    for (int d = 0; d <= (solver.HasCycles() ? opt.penalty_doublings : 0); ++d, sigma *= 2) {
      solver.Run(Phase::kObjective, sigma);
      if (solver.ConstraintResidual() < opt.feasibility_tolerance) break;
    }
    double mm, deg;
    TargetErrors(prog, solver.Poses()[prog.target], mm, deg);
    if (!prog.target_match_rotation) deg = 0;
    out.objective_seconds += objective_time.Seconds();
    const double obj = mm * mm + std::pow(opt.target_mm_per_rad * deg * M_PI / 180, 2);
    if (obj < best_obj) {
      best_obj = obj;
      best = solver.blocks();
    }
    if (mm < opt.early_exit_mm && deg < 1.0) break;
    if (++objective_starts >= opt.objective_starts) break;
  }
  if (!out.feasible) {
    out.messages.push_back(prog.file + ": cycles do not close after " + std::to_string(out.starts_tried) + " starts");
    solver.blocks() = closest;
    out.constraint_residual = closest_c;
    out.poses = solver.Poses();
    return false;
  }
  solver.blocks() = best;
  return true;
}

// Step 2's runs after the continuation. With the active set, step 2 runs in
// rounds of at most kActiveSetRound iterations and updates the set after
// each, so a parameter that runs into a bound is held there within a round
// instead of LM creeping along it; a round that ends at its cap with the set
// unchanged goes on, up to relaxation_max_iterations in all since the last
// change. With static friction, the slides whose load leaves the friction
// cone are let go and the relaxation runs again.
void RelaxToRest(const SolveOptions& opt, Solver& solver, SolveSummary& out) {
  int since_change = 0;
  for (;;) {
    const ceres::Solver::Summary rs = solver.Run(Phase::kRelaxation, opt.relaxation_penalty, nullptr, nullptr,
                                                 opt.relaxation_active_set ? kActiveSetRound : 0);
    out.relaxation_termination = ceres::TerminationTypeToString(rs.termination_type);
    out.relaxation_iterations += static_cast<int>(rs.iterations.size()) - 1;
    ++out.relaxation_runs;
    if (opt.relaxation_active_set && out.relaxation_runs < kMaxRelaxationRuns) {
      if (solver.UpdateActiveSet() > 0) {
        since_change = 0;
        continue;
      }
      since_change += static_cast<int>(rs.iterations.size()) - 1;
      if (rs.termination_type == ceres::NO_CONVERGENCE && since_change < opt.relaxation_max_iterations) continue;
    }
    if (!opt.slide_friction || solver.ReleaseSlipping() == 0) break;
    since_change = 0;
  }
}

// Step 2 (FabHacks Sec. 4.3.3): relaxation under gravity from step 1's
// parameters (moved by `perturbation`, SolvePerturbedRelaxation's), then
// what falls apart and the slides' loads.
void Relax(const SolveOptions& opt, double perturbation, Solver& solver, SolveSummary& out) {
  if (perturbation != 0) solver.Perturb(perturbation);
  solver.SetRelaxationAnchor();
  const Stopwatch relaxation_time;
  // Static friction along rods: relax with every slide held, let go of
  // those whose load leaves the friction cone and relax again from there,
  // until every slide still held is inside it (at most one more relaxation
  // per slide: a slide let go is not held again).
  if (opt.slide_friction) solver.StickSlides();
  // Optionally the reference implementation's continuation first
  // (SolveOptions::relaxation_target_weight): the target term w·‖error‖²,
  // w divided by 10 at every convergence, the slides held throughout;
  // then the energy alone.
  for (double w = opt.relaxation_target_weight; w > opt.relaxation_target_weight_end; w *= 0.1) {
    solver.SetRelaxationTargetWeight(w);
    const ceres::Solver::Summary rs = solver.Run(Phase::kRelaxation, opt.relaxation_penalty);
    out.relaxation_iterations += static_cast<int>(rs.iterations.size()) - 1;
    ++out.relaxation_runs;
  }
  solver.SetRelaxationTargetWeight(0);
  RelaxToRest(opt, solver, out);
  out.relaxation_seconds = relaxation_time.Seconds();
  out.falls_apart = solver.FallsApart();
  out.slides = solver.SlideReport();
}

// The final poses, parameters and target errors, the target's motion in
// step 2, resting contacts, and the verdicts.
void Report(const Program& prog, const SolveOptions& opt, Solver& solver, SolveSummary& out) {
  out.poses = solver.Poses();
  for (size_t e = 0; e < prog.connections.size(); ++e) {
    std::vector<double> s;
    const auto& c = prog.connections[e];
    for (size_t i = 0; i < c.params_a.size(); ++i)
      s.push_back(c.params_a[i].held ? c.params_a[i].init : solver.blocks()[2 * e][i]);
    for (size_t i = 0; i < c.params_b.size(); ++i)
      s.push_back(c.params_b[i].held ? c.params_b[i].init : solver.blocks()[2 * e + 1][i]);
    out.params.push_back(s);
  }
  TargetErrors(prog, out.poses[prog.target], out.final_target_error_mm, out.final_target_error_deg);
  {
    const Eigen::Matrix4d off = prog.TargetOffset();
    const Eigen::Matrix4d q1 = out.step1_poses[prog.target].matrix() * off, q2 = out.poses[prog.target].matrix() * off;
    out.relax_displacement_mm = (q2.topRightCorner<3, 1>() - q1.topRightCorner<3, 1>()).norm();
    out.relax_rotation_deg = RotationAngleDeg(q2.topLeftCorner<3, 3>(), q1.topLeftCorner<3, 3>());
  }
  if (opt.relax) {
    const auto tipped = internal::RestingFailures(prog, out.poses, opt.friction_angle_deg);
    out.falls_apart.insert(out.falls_apart.end(), tipped.begin(), tipped.end());
  }
  // FabHacks Sec. 4.3.3: the assembly is reported as falling apart when a
  // connector slides off (above) — and, for a part resting on another, when
  // it slides off or tips over. Relaxation motion alone is not a failure (in the paper's
  // frictionless model the demo slides its S-hook to the end of the hanger bar and works).
  out.stable = opt.relax && out.falls_apart.empty();
  out.target_reached = out.final_target_error_mm <= opt.target_tolerance_mm &&
                       (!prog.target_match_rotation || out.final_target_error_deg <= opt.target_tolerance_deg);
}

SolveSummary Solve(const Program& prog, const SolveOptions& opt, double perturbation) {
  const Stopwatch total_time;
  SolveSummary out;
  const PrecheckSummary pre = Precheck(prog);
  out.precheck_seconds = total_time.Seconds();
  for (const auto& i : pre.issues) out.messages.push_back(i.message);
  out.prechecks_passed = pre.ok;
  auto finish = [&]() {
    out.seconds = total_time.Seconds();
    return out;
  };
  if (!pre.ok) return finish();
  Solver solver(prog, opt);
  if (!Step1(prog, opt, solver, out)) return finish();
  out.constraint_residual = solver.ConstraintResidual();
  out.step1_poses = solver.Poses();
  TargetErrors(prog, out.step1_poses[prog.target], out.step1_target_error_mm, out.step1_target_error_deg);
  if (opt.relax) Relax(opt, perturbation, solver, out);
  Report(prog, opt, solver, out);
  return finish();
}

}  // namespace

internal::JacobianCheck internal::CheckJacobian(const Program& program, int start, int phase,
                                                const SolveOptions& options) {
  Solver solver(program, options);
  solver.SetStart(start);
  const Phase p = static_cast<Phase>(phase);
  return solver.CheckJacobian(p, p == Phase::kObjective    ? options.penalty_start
                                 : p == Phase::kRelaxation ? options.relaxation_penalty
                                                           : 1.0);
}

SolveSummary SolveAssembly(const Program& prog, const SolveOptions& opt) { return Solve(prog, opt, 0.0); }

SolveSummary internal::SolvePerturbedRelaxation(const Program& prog, double delta, const SolveOptions& opt) {
  return Solve(prog, opt, delta);
}

}  // namespace fabatlas::assembly
