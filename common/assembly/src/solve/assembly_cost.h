// solve/assembly_cost.h (internal to fabatlas_assembly) — the residuals of
// assembly_residual.h with analytic Jacobians, for Ceres.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include <Eigen/Core>
#include <ceres/ceres.h>

#include "assembly_residual.h"
#include "kinematics.h"

namespace fabatlas::assembly::internal {

// Connector frame M = base·M_local(s) and its partial derivatives dM/ds_i of
// one parameter block (i = 0..3), from one pass of 4-wide forward-mode Jets
// through the local frame only (the constant base frame stays in double).
struct FrameDerivatives {
  Eigen::Matrix4d m;
  std::array<Eigen::Matrix4d, internal::kParamBlock> d;
};

FrameDerivatives ConnectorFrameDerivatives(const Eigen::Matrix4d& base, const Primitive& p, const double* s,
                                           int sym_axis);

// AssemblyResidual with analytic Jacobians (same residuals). Forward
// kinematics makes each part pose a product of per-connection frames, so a
// parameter s of tree connection e (child c) changes every pose of c's
// subtree by the same world-frame factor: dP_d/ds = G·P_d with
// G = (dP_c/ds)·P_c⁻¹. A parameter of a closing connection only enters its
// own closure residual. Costs a few 4×4 double products per parameter instead
// of carrying derivative vectors through the whole chain (autodiff).
class AssemblyCost : public ceres::CostFunction {
 public:
  explicit AssemblyCost(AssemblyResidual f);
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override;

 private:
  // What the Jacobian's parts share of one evaluation.
  struct Frames {
    std::vector<FrameDerivatives> connector;  // per parameter block (derivatives where a Jacobian is asked for)
    std::vector<Mat4<double>> pose;           // per part
    std::vector<Eigen::Matrix4d> fa, fb;      // closure frames P_a·M_a·A, P_b·M_b per closing connection
  };
  Frames FramesAt(double const* const* params, double** jacobians) const;
  // Rows of the residual blocks (closures first, then spacing, target, energy).
  int SpacingRow() const;
  int TargetRow() const;
  int EnergyRow() const;
  void TreeJacobians(const Frames& frames, double** jacobians) const;
  void SubtreeRows(std::size_t t, const Eigen::Matrix4d& g, int i, const Frames& frames, double* jac) const;
  void ClosingJacobians(const Frames& frames, double** jacobians) const;
  void SpacingJacobians(double const* const* params, double** jacobians) const;

  AssemblyResidual f_;
  std::vector<std::vector<char>> subtree_;  // per tree edge, per part
  std::vector<std::array<bool, internal::kParamBlock>> used_;
};

}  // namespace fabatlas::assembly::internal
