// solve/solver.h (internal to fabatlas_assembly) — the state of one assembly
// solve (FabHacks Sec. 4.3) and its steps: start points (start_points.cc),
// Ceres runs of each phase (solver.cc), static friction along rods
// (friction.cc) and the relaxation's active set and what falls apart
// (active_set.cc). solve.cc drives it.
#pragma once

#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <ceres/ceres.h>

#include "assembly_residual.h"
#include "fabatlas/assembly/program.h"
#include "fabatlas/assembly/solve.h"
#include "kinematics.h"
#include "solve_internal.h"
#include "target_form.h"

namespace fabatlas::assembly::internal {

// One chain of the chain-by-chain initial guess (Solver::SetChainStart):
// which connections' parameters move, and which cycles are closed.
struct Chain {
  std::vector<char> free;             // per connection
  std::vector<double> closing_scale;  // per closing connection: 1 closed by this chain, 0 ignored
};

// One slide along a rod, tube or edge that static friction acts on
// (SolveOptions::slide_friction): parameter `index` of block `block`.
struct SlideState {
  int block, index;
  bool stuck = false;            // held at its value by friction
  double axial = 0, normal = 0;  // load along / across the axis (J/mm = kN), last evaluated
  double angle_deg = 0;          // atan(axial / normal), degrees, last evaluated
  double slip_angle_deg = 0;     // the angle at which it was let go
};

// The connection parameters of one program and the runs that move them.
// Not thread-safe; one per solve.
class Solver {
 public:
  Solver(const Program& prog, const SolveOptions& opt);

  bool HasCycles() const { return !kin_.closing.empty() || !spacing_.empty(); }
  bool ClosesCycles() const { return !kin_.closing.empty(); }

  // Start points (start_points.cc).
  // Connection parameter values of start k (k = 0: box centre; else Halton).
  void SetStart(int k);
  // Chain-by-chain initial guess; returns the chains solved.
  int SetChainStart();

  // Runs (solver.cc).
  // One Ceres run of `phase` with penalty sigma from the current parameters
  // (moved in place); `keep` receives the problem, `chain` limits what moves,
  // `max_iterations` > 0 replaces the options' cap.
  ceres::Solver::Summary Run(Phase phase, double sigma, std::unique_ptr<ceres::Problem>* keep = nullptr,
                             const Chain* chain = nullptr, int max_iterations = 0);
  // C = Σ‖g_j‖² + C_m at the current parameters (unit weights).
  double ConstraintResidual();
  // Every part's pose at the current parameters (mm).
  std::vector<Eigen::Isometry3d> Poses() const;
  std::vector<Block>& blocks() { return blocks_; }
  // Weight w (J per mm²) of the target term w·‖target error‖² in the
  // relaxation (SolveOptions::relaxation_target_weight); 0 removes it.
  void SetRelaxationTargetWeight(double w) { relax_target_scale_ = std::sqrt(2 * w); }
  // Step 2 starts here: the gauge anchor is the current parameters.
  void SetRelaxationAnchor() { anchor_ = blocks_; }
  // Adds `delta` to every parameter that is not held, clamped to the
  // parameter's bounds (SolvePerturbedRelaxation).
  void Perturb(double delta);
  // Analytic Jacobian of one phase against autodiff at the current parameters.
  internal::JacobianCheck CheckJacobian(Phase phase, double sigma);

  // Static friction along rods (friction.cc).
  void StickSlides();
  int ReleaseSlipping();
  std::vector<SolveSummary::Slide> SlideReport() const;

  // The relaxation's active set and what falls apart (active_set.cc).
  int UpdateActiveSet();
  std::vector<std::string> FallsApart();

 private:
  std::array<double, internal::kParamBlock> Units(int b) const;
  void SetStuck(SlideState& sl, bool stuck);
  const SlideState* FindSlide(int b, int i) const;
  void EvaluateSlideLoads();
  void PartForces(const std::vector<Eigen::Isometry3d>& pose, std::vector<Eigen::Vector3d>& force,
                  std::vector<Eigen::Vector3d>& closing_force) const;
  std::vector<double> SlideGradients();
  Eigen::Vector3d SlideForce(int e, const std::vector<Eigen::Vector3d>& force,
                             const std::vector<Eigen::Vector3d>& closing_force) const;
  std::vector<double> EnergyGradient();
  const std::vector<ParamSpec>& Spec(int b) const {
    const auto& c = prog_.connections[b / 2];
    return b % 2 == 0 ? c.params_a : c.params_b;
  }
  std::vector<double*> Pointers();
  AssemblyResidual Residual(Phase phase, double sigma) const;
  void Build(ceres::Problem& problem, Phase phase, double sigma, const Chain* chain = nullptr);
  ceres::Solver::Options OptionsOf(Phase phase, int max_iterations) const;

  const Program& prog_;
  const SolveOptions& opt_;
  Kinematics kin_;
  std::vector<Block> blocks_;
  std::vector<SpacingTerm> spacing_;
  std::vector<EnergyTerm> energy_;
  TargetForm target_;
  std::vector<Block> anchor_;                      // gauge anchor of the relaxation
  std::vector<SlideState> slides_;                 // static friction along rods (StickSlides)
  double relax_target_scale_ = 0;                  // SetRelaxationTargetWeight
  std::vector<std::pair<int, int>> pinned_;        // active set: (block, index) held at a bound
  static constexpr double kForceTolerance = 1e-9;  // J per unit
};

}  // namespace fabatlas::assembly::internal
