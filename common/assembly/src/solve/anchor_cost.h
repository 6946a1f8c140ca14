// solve/anchor_cost.h (internal to fabatlas_assembly) — the relaxation's
// gauge fix, a weak spring to where it starts.
#pragma once

#include <array>
#include <cmath>

#include <ceres/ceres.h>

#include "connector_frames.h"

namespace fabatlas::assembly::internal {

// Gauge fix of the relaxation: ½k‖s − s₀‖² for one parameter block, s₀ the
// parameters the relaxation starts from (step 1). A hanging part whose centre
// of mass is below its support may turn about the vertical at no energy cost;
// without this term that turn is left to round-off and the relaxed pose is
// not reproducible. k (J per unit², degrees for angles; default 1e-9) is far
// below the gravity stiffness of a swing, m g L/1000·(π/180)² (5e-7 J/deg²
// for 5 g on a 30 mm lever), so it picks one of equivalent equilibria and
// moves a true one by a relative ≲ k / that stiffness.
class AnchorCost : public ceres::SizedCostFunction<internal::kParamBlock, internal::kParamBlock> {
 public:
  // `unit`: mm per unit of each parameter (a slide parameter t moves the
  // contact by the primitive's length per unit), 1 for angles (degrees).
  AnchorCost(const std::array<double, internal::kParamBlock>& anchor, double stiffness,
             const std::array<double, internal::kParamBlock>& unit)
      : anchor_(anchor) {
    for (int i = 0; i < internal::kParamBlock; ++i) w_[i] = std::sqrt(stiffness) * unit[i];
  }
  bool Evaluate(double const* const* x, double* r, double** jac) const override {
    for (int i = 0; i < internal::kParamBlock; ++i) r[i] = w_[i] * (x[0][i] - anchor_[i]);
    if (jac && jac[0])
      for (int i = 0; i < internal::kParamBlock * internal::kParamBlock; ++i)
        jac[0][i] = i % (internal::kParamBlock + 1) == 0 ? w_[i / internal::kParamBlock] : 0.0;
    return true;
  }

 private:
  std::array<double, internal::kParamBlock> anchor_;
  std::array<double, internal::kParamBlock> w_;
};

}  // namespace fabatlas::assembly::internal
