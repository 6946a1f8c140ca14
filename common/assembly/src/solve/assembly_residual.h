// solve/assembly_residual.h (internal to fabatlas_assembly) — every residual of
// one phase of the solve (FabHacks Sec. 4.3): cycle closure, the spacing of
// connections sharing a rod (Sec. 4.3.1), the target and, in the relaxation,
// the gravitational potential; templated for Ceres autodiff (the analytic
// Jacobian is assembly_cost.h's).
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "kinematics.h"
#include "target_form.h"

namespace fabatlas::assembly::internal {

// A phase of the solve: step 1's feasibility and objective, step 2's
// relaxation.
enum class Phase { kFeasibility, kObjective, kRelaxation };

struct SpacingTerm {
  int block1, block2;  // parameter block indices (2e + side)
  double length, half_widths;
};

struct EnergyTerm {
  int part;
  Eigen::Vector3d com;
  double scale;  // sqrt(m g / (1000 D))
  double datum;  // −D (mm), see AssemblyResidual
};

// All residuals of one phase as one cost over all parameter blocks.
struct AssemblyResidual {
  const Kinematics* kin;
  Phase phase;
  double closure_weight, rot_scale, target_rot_scale;
  // Relaxation only: residual scale of the target term (0: none), see
  // SolveOptions::relaxation_target_weight.
  double relax_target_scale = 0;
  bool HasTargetRows() const {
    return phase == Phase::kObjective || (phase == Phase::kRelaxation && relax_target_scale > 0);
  }
  double TargetScale() const { return phase == Phase::kObjective ? 1.0 : relax_target_scale; }
  std::vector<SpacingTerm> spacing;
  std::vector<EnergyTerm> energy;
  const TargetForm* target = nullptr;
  // Per closing connection (kin->closing order): multiplies its closure
  // residuals; empty = all 1. A chain solve (Solver::SetChainStart) switches
  // off the cycles it does not close.
  std::vector<double> closing_scale;
  double ClosingScale(size_t k) const { return closing_scale.empty() ? 1.0 : closing_scale[k]; }

  int NumResiduals() const {
    return 12 * static_cast<int>(kin->closing.size()) + static_cast<int>(spacing.size()) + (HasTargetRows() ? 12 : 0) +
           (phase == Phase::kRelaxation ? static_cast<int>(energy.size()) : 0);
  }

  template <typename T>
  bool operator()(T const* const* params, T* r) const {
    const std::vector<Mat4<T>> p = kin->Poses<T>(params);
    int k = 0;
    for (size_t ci = 0; ci < kin->closing.size(); ++ci) {
      const int e = kin->closing[ci];
      const auto& c = kin->prog->connections[e];
      Mat4<T> ma, mb;
      kin->Frames<T>(e, params[2 * e], params[2 * e + 1], ma, mb);
      const Mat4<T> fa = p[c.part_a] * ma * kin->align[e].template cast<T>();
      const Mat4<T> fb = p[c.part_b] * mb;
      const double w = closure_weight * ClosingScale(ci);
      for (int i = 0; i < 3; ++i) r[k++] = T(w) * (fa(i, 3) - fb(i, 3));
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r[k++] = T(w * rot_scale) * (fa(i, j) - fb(i, j));
    }
    // Multi-connection spacing (FabHacks, 4.3.1): f = |t1 − t2|·L − (w1 + w2)/2, f² if f < 0.
    for (const auto& s : spacing) {
      T d = params[s.block1][0] - params[s.block2][0];
      if (d < T(0)) d = -d;
      const T f = d * T(s.length) - T(s.half_widths);
      r[k++] = f < T(0) ? T(closure_weight) * f : T(0);
    }
    if (HasTargetRows()) {
      const Mat4<T> q = p[kin->prog->target] * target->offset.template cast<T>();
      const double ts = TargetScale();
      for (int i = 0; i < 3; ++i) r[k++] = T(ts) * (q(i, 3) - T(target->t[i]));
      T w[9];
      target->RotationResidual<T>(q.template topLeftCorner<3, 3>(), w);
      for (int i = 0; i < 9; ++i) r[k++] = T(ts * target_rot_scale) * w[i];
    }
    if (phase == Phase::kRelaxation) {
      // Potential m·g·z (J, z in mm/1000) as ½r² = m g (z + D)² / (2000 D):
      // gradient m g (z + D)/(1000 D) = m g/1000 up to a relative |z|/D < 1e-2.
      for (const auto& en : energy) {
        const Mat4<T>& q = p[en.part];
        T z = q(2, 3);
        for (int i = 0; i < 3; ++i) z += q(2, i) * T(en.com[i]);
        r[k++] = T(en.scale) * (z - T(en.datum));
      }
    }
    return true;
  }
};

}  // namespace fabatlas::assembly::internal
