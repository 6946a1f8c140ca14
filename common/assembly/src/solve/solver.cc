// The assembly solver's state and its Ceres runs (solve/solver.h): the
// kinematics, spacing and energy terms of a program, the problem of each
// phase with its bounds, held parameters and gauge anchor, and the Jacobian
// check.
#include "solver.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "anchor_cost.h"
#include "assembly_cost.h"
#include "stopping_rules.h"

namespace fabatlas::assembly::internal {

namespace {

// The program's reduced coordinates: frames, alignments, held parameters
// and the spanning tree.
Kinematics KinematicsOf(const Program& prog) {
  Kinematics kin;
  const int m = static_cast<int>(prog.connections.size());
  kin.prog = &prog;
  kin.env = ToIsometry(prog.environment_frame).matrix();
  for (const auto& c : prog.connections) {
    kin.base_a.push_back(ToIsometry(prog.PrimitiveA(c).frame).matrix());
    kin.base_b.push_back(ToIsometry(prog.PrimitiveB(c).frame).matrix());
    Eigen::Matrix4d a = Eigen::Matrix4d::Identity();
    a.topLeftCorner<3, 3>() = c.align;
    kin.align.push_back(a);
    for (int side = 0; side < 2; ++side) {
      const auto& specs = side == 0 ? c.params_a : c.params_b;
      std::array<bool, internal::kParamBlock> held{};
      std::array<double, internal::kParamBlock> value{};
      for (size_t i = 0; i < specs.size(); ++i) held[i] = specs[i].held, value[i] = specs[i].init;
      kin.held.push_back(held);
      kin.held_value.push_back(value);
      kin.sym_axis.push_back(side == 0 ? c.symmetry_axis_a : -1);
    }
  }
  // The spanning tree is the program's attach steps (each places its new
  // part b from the placed part a); connect steps close cycles.
  for (int e = 0; e < m; ++e) {
    if (prog.connections[e].closing)
      kin.closing.push_back(e);
    else
      kin.tree.push_back({e, prog.connections[e].part_b});
  }
  return kin;
}

// Spacing terms for connections sharing one rod/tube/edge.
std::vector<SpacingTerm> SpacingTerms(const Program& prog) {
  std::vector<SpacingTerm> spacing;
  const int m = static_cast<int>(prog.connections.size());
  for (int b1 = 0; b1 < 2 * m; ++b1)
    for (int b2 = b1 + 1; b2 < 2 * m; ++b2) {
      const auto& c1 = prog.connections[b1 / 2];
      const auto& c2 = prog.connections[b2 / 2];
      if (b1 / 2 == b2 / 2) continue;
      const int i1 = b1 % 2 == 0 ? c1.part_a : c1.part_b, i2 = b2 % 2 == 0 ? c2.part_a : c2.part_b;
      const std::string& n1 = b1 % 2 == 0 ? c1.primitive_a : c1.primitive_b;
      const std::string& n2 = b2 % 2 == 0 ? c2.primitive_a : c2.primitive_b;
      if (i1 != i2 || n1 != n2) continue;
      const Primitive& host = *prog.PartOf(i1).Find(n1);
      if (host.type != PrimitiveType::kRod && host.type != PrimitiveType::kTube && host.type != PrimitiveType::kEdge)
        continue;
      const Primitive& g1 = b1 % 2 == 0 ? prog.PrimitiveB(c1) : prog.PrimitiveA(c1);
      const Primitive& g2 = b2 % 2 == 0 ? prog.PrimitiveB(c2) : prog.PrimitiveA(c2);
      spacing.push_back(
          {b1, b2, host.Shape("length"), 0.5 * (g1.OccupiedSize(host.type) + g2.OccupiedSize(host.type))});
    }
  return spacing;
}

// The gravitational potential of every part with mass (relaxation).
std::vector<EnergyTerm> EnergyTerms(const Program& prog, const SolveOptions& opt) {
  std::vector<EnergyTerm> energy;
  const int n = static_cast<int>(prog.instances.size());
  for (int i = 1; i < n; ++i) {
    const Part& part = prog.PartOf(i);
    if (part.mass <= 0) continue;
    const double mass_kg = part.mass * 1e-6;  // mm³ × 1 g/cm³
    energy.push_back({i, part.centre_of_mass, std::sqrt(mass_kg * opt.gravity / (1000.0 * opt.relaxation_datum_mm)),
                      -opt.relaxation_datum_mm});
  }
  return energy;
}

}  // namespace

Solver::Solver(const Program& prog, const SolveOptions& opt)
    : prog_(prog), opt_(opt), kin_(KinematicsOf(prog)), spacing_(SpacingTerms(prog)), energy_(EnergyTerms(prog, opt)) {
  blocks_.assign(2 * prog.connections.size(), Block{0, 0, 0, 0});
  target_ = TargetForm::Of(prog);
}

// The Ceres options of a run of `phase`.
ceres::Solver::Options Solver::OptionsOf(Phase phase, int max_iterations) const {
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::DENSE_QR;
  o.max_num_iterations = max_iterations > 0            ? max_iterations
                         : phase == Phase::kRelaxation ? opt_.relaxation_max_iterations
                                                       : opt_.max_iterations;
  o.num_threads = 1;
  o.logging_type = ceres::SILENT;
  o.function_tolerance = 1e-12;
  o.gradient_tolerance = 1e-12;
  o.parameter_tolerance = 1e-10;
  if (phase == Phase::kRelaxation) {
    // The energy landscape along a hanging chain is flat (see SolveOptions):
    // stop on the projected gradient and on the step, not on a relative
    // cost change (the cost carries the energy datum, so 1e-12 of it is
    // far above the energy differences still being resolved).
    o.function_tolerance = opt_.relaxation_function_tolerance;
    o.gradient_tolerance = opt_.relaxation_gradient_tolerance;
    o.parameter_tolerance = opt_.relaxation_parameter_tolerance;
  }
  return o;
}

ceres::Solver::Summary Solver::Run(Phase phase, double sigma, std::unique_ptr<ceres::Problem>* keep, const Chain* chain,
                                   int max_iterations) {
  auto problem = std::make_unique<ceres::Problem>();
  Build(*problem, phase, sigma, chain);
  ceres::Solver::Options o = OptionsOf(phase, max_iterations);
  StallCallback stall(opt_.stall_window, opt_.stall_slope, opt_.feasibility_tolerance);
  if (phase == Phase::kFeasibility) o.callbacks.push_back(&stall);
  RelaxationWindow window(blocks_, opt_.relaxation_window, opt_.relaxation_window_motion);
  if (phase == Phase::kRelaxation && opt_.relaxation_window > 0) {
    o.update_state_every_iteration = true;
    o.callbacks.push_back(&window);
  }

  ceres::Solver::Summary s;
  ceres::Solve(o, problem.get(), &s);
  // A held parameter's value is its held value (the gauge anchor may have
  // moved the unused block entry).
  for (size_t b = 0; b < blocks_.size(); ++b)
    for (int i = 0; i < internal::kParamBlock; ++i)
      if (kin_.held[b][i]) blocks_[b][i] = kin_.held_value[b][i];
  if (std::getenv("FABATLAS_ASSEMBLY_DEBUG"))
    std::fprintf(stderr, "phase %d sigma %g: %s (%s)\n", static_cast<int>(phase), sigma, s.BriefReport().c_str(),
                 s.message.c_str());
  if (keep) *keep = std::move(problem);
  return s;
}

double Solver::ConstraintResidual() {
  if (!HasCycles()) return 0;
  AssemblyResidual f = Residual(Phase::kFeasibility, 1.0);
  std::vector<double> r(f.NumResiduals());
  f(Pointers().data(), r.data());
  double c = 0;
  for (double x : r) c += x * x;
  return c;
}

std::vector<Eigen::Isometry3d> Solver::Poses() const {
  std::vector<const double*> ptr;
  for (const auto& b : blocks_) ptr.push_back(b.data());
  const auto p = kin_.Poses<double>(ptr.data());
  std::vector<Eigen::Isometry3d> out;
  for (const auto& m : p) {
    Eigen::Isometry3d t;
    t.matrix() = m;
    out.push_back(t);
  }
  return out;
}

void Solver::Perturb(double delta) {
  for (size_t b = 0; b < blocks_.size(); ++b) {
    const auto& specs = Spec(static_cast<int>(b));
    for (size_t i = 0; i < specs.size(); ++i) {
      if (specs[i].held) continue;
      double& x = blocks_[b][i];
      x += delta;
      if (specs[i].kind != ParamKind::kUnbounded) x = std::clamp(x, specs[i].min, specs[i].max);
    }
    if (kin_.sym_axis[b] >= 0) blocks_[b][3] += delta;
  }
}

internal::JacobianCheck Solver::CheckJacobian(Phase phase, double sigma) {
  internal::JacobianCheck out;
  AssemblyCost analytic(Residual(phase, sigma));
  if (analytic.num_residuals() == 0) return out;  // no cycles: nothing to close
  ceres::DynamicAutoDiffCostFunction<AssemblyResidual, 16> autodiff(new AssemblyResidual(Residual(phase, sigma)));
  for (size_t b = 0; b < blocks_.size(); ++b) autodiff.AddParameterBlock(internal::kParamBlock);
  autodiff.SetNumResiduals(analytic.num_residuals());
  const int nr = analytic.num_residuals();
  out.residuals = nr;
  out.parameters = internal::kParamBlock * static_cast<int>(blocks_.size());
  std::vector<std::vector<double>> j1(blocks_.size(), std::vector<double>(nr * internal::kParamBlock)), j2 = j1;
  std::vector<double*> p1, p2;
  for (size_t b = 0; b < blocks_.size(); ++b) p1.push_back(j1[b].data()), p2.push_back(j2[b].data());
  std::vector<double> r1(nr), r2(nr);
  const std::vector<double*> x = Pointers();
  analytic.Evaluate(x.data(), r1.data(), p1.data());
  autodiff.Evaluate(x.data(), r2.data(), p2.data());
  for (size_t b = 0; b < blocks_.size(); ++b)
    for (size_t i = 0; i < j1[b].size(); ++i) {
      out.max_error = std::max(out.max_error, std::abs(j1[b][i] - j2[b][i]));
      out.max_entry = std::max(out.max_entry, std::abs(j2[b][i]));
    }
  for (int i = 0; i < nr; ++i) out.max_residual_error = std::max(out.max_residual_error, std::abs(r1[i] - r2[i]));
  return out;
}

// mm per unit of each parameter of block b (slide parameters: the length
// they run along; angles: 1, degrees).
std::array<double, internal::kParamBlock> Solver::Units(int b) const {
  std::array<double, internal::kParamBlock> u{1, 1, 1, 1};
  const auto& c = prog_.connections[b / 2];
  const Primitive& p = b % 2 == 0 ? prog_.PrimitiveA(c) : prog_.PrimitiveB(c);
  const auto& specs = Spec(b);
  for (size_t i = 0; i < specs.size(); ++i) {
    if (specs[i].name == "t")
      u[i] = p.Shape("length");
    else if (specs[i].name == "t1")
      u[i] = p.Shape("width");
    else if (specs[i].name == "t2")
      u[i] = p.Shape("length");
  }
  return u;
}

std::vector<double*> Solver::Pointers() {
  std::vector<double*> ptr;
  for (auto& b : blocks_) ptr.push_back(b.data());
  return ptr;
}

AssemblyResidual Solver::Residual(Phase phase, double sigma) const {
  AssemblyResidual f;
  f.kin = &kin_;
  f.phase = phase;
  f.closure_weight = phase == Phase::kFeasibility ? 1.0
                     : phase == Phase::kObjective ? std::sqrt(sigma)
                                                  : std::sqrt(2 * sigma);
  f.rot_scale = opt_.rotation_scale_mm;
  f.target_rot_scale = prog_.target_match_rotation ? opt_.target_mm_per_rad : 0.0;
  if (phase == Phase::kRelaxation) f.relax_target_scale = relax_target_scale_;
  f.spacing = spacing_;
  f.energy = energy_;
  f.target = &target_;
  return f;
}

void Solver::Build(ceres::Problem& problem, Phase phase, double sigma, const Chain* chain) {
  AssemblyResidual f = Residual(phase, sigma);
  if (chain) f.closing_scale = chain->closing_scale;
  problem.AddResidualBlock(new AssemblyCost(std::move(f)), nullptr, Pointers());
  for (size_t b = 0; b < blocks_.size(); ++b) {
    const auto& c = prog_.connections[b / 2];
    double* s = blocks_[b].data();
    if (chain && !chain->free[b / 2]) {
      problem.SetParameterBlockConstant(s);
      continue;
    }
    const auto& specs = Spec(static_cast<int>(b));
    for (size_t i = 0; i < specs.size(); ++i)
      if (specs[i].kind != ParamKind::kUnbounded && !specs[i].held) {
        problem.SetParameterLowerBound(s, static_cast<int>(i), specs[i].min);
        problem.SetParameterUpperBound(s, static_cast<int>(i), specs[i].max);
      }
    // A clip clamps its partner: both sides of a clip connection are held
    // during relaxation, as are is_fixed connections (PARTS.md §1.10).
    const bool hold = phase == Phase::kRelaxation && c.held_in_relaxation;
    if (hold)
      problem.SetParameterBlockConstant(s);
    else if (phase == Phase::kRelaxation && opt_.relaxation_anchor_stiffness > 0)
      problem.AddResidualBlock(new AnchorCost(anchor_[b], opt_.relaxation_anchor_stiffness, Units(b)), nullptr, s);
  }
}

}  // namespace fabatlas::assembly::internal
