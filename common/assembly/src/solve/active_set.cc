// The relaxation's active set and what falls apart after it (solve/solver.h;
// FabHacks Sec. 4.3.3).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "assembly_cost.h"
#include "solver.h"

namespace fabatlas::assembly::internal {

// BOUNDED_AND_OPEN parameters at a bound with outward energy gradient
// (FabHacks, 4.3.3).
// With slide friction, a connector on a rod pushed against an open end
// stays on when its load there is inside the friction cone.
std::vector<std::string> Solver::FallsApart() {
  std::vector<std::string> out;
  if (opt_.slide_friction) EvaluateSlideLoads();
  const std::vector<double> grad = EnergyGradient();  // gravity + closure, not the gauge anchor
  for (size_t b = 0; b < blocks_.size(); ++b) {
    if (prog_.connections[b / 2].held_in_relaxation) continue;
    const auto& c = prog_.connections[b / 2];
    const std::string where = b % 2 == 0 ? prog_.instances[c.part_a].name + "." + c.primitive_a
                                         : prog_.instances[c.part_b].name + "." + c.primitive_b;
    const auto& specs = Spec(static_cast<int>(b));
    for (size_t i = 0; i < specs.size(); ++i) {
      const bool pinned = std::find(pinned_.begin(), pinned_.end(), std::make_pair(int(b), int(i))) != pinned_.end();
      if (specs[i].kind != ParamKind::kBoundedAndOpen || specs[i].held || (kin_.held[b][i] && !pinned)) continue;
      const SlideState* slide = FindSlide(static_cast<int>(b), static_cast<int>(i));
      if (slide && slide->angle_deg <= opt_.friction_angle_deg) continue;
      const double x = blocks_[b][i], g = grad[internal::kParamBlock * b + i];
      const double eps = 1e-6 * (specs[i].max - specs[i].min);
      if (std::getenv("FABATLAS_ASSEMBLY_DEBUG") && (x <= specs[i].min + eps || x >= specs[i].max - eps))
        std::fprintf(stderr, "at bound: %s.%s = %g, gradient %g\n", where.c_str(), specs[i].name.c_str(), x, g);
      if (x <= specs[i].min + eps && g > kForceTolerance && !specs[i].blocked_min)
        out.push_back(where + "." + specs[i].name + " at min");
      else if (x >= specs[i].max - eps && g < -kForceTolerance && !specs[i].blocked_max)
        out.push_back(where + "." + specs[i].name + " at max");
    }
  }
  return out;
}

// Active set of the relaxation (SolveOptions::relaxation_active_set; the
// reference's active-set Newton): pins every bounded parameter that the
// relaxation left at a bound with the energy pushing it out of its
// interval; if none, unpins the pinned one the energy pushes back in
// hardest (per mm or degree; one at a time, as an active-set method drops
// one constraint per step — dropping all at once cycles on the reading
// nook's ring links). A parameter held otherwise (base form, held
// connection, stuck slide) is not touched. Returns how many changed; the
// relaxation then runs again with the set held. Bounded
// Levenberg-Marquardt alone creeps along a bound it keeps running into.
int Solver::UpdateActiveSet() {
  const std::vector<double> grad = EnergyGradient();
  int pinned = 0;
  int worst = -1;  // the pinned parameter pushed back in hardest
  double worst_g = kForceTolerance;
  for (size_t b = 0; b < blocks_.size(); ++b) {
    if (prog_.connections[b / 2].held_in_relaxation) continue;
    const auto& specs = Spec(static_cast<int>(b));
    const auto units = Units(static_cast<int>(b));
    for (size_t i = 0; i < specs.size(); ++i) {
      if (specs[i].kind == ParamKind::kUnbounded || specs[i].held) continue;
      const double g = grad[internal::kParamBlock * b + i], x = blocks_[b][i];
      const double eps = 1e-6 * (specs[i].max - specs[i].min);
      const auto it = std::find(pinned_.begin(), pinned_.end(), std::make_pair(int(b), int(i)));
      if (it != pinned_.end()) {
        const double inward = (x <= specs[i].min + eps ? -g : g) / units[i];
        if (inward > worst_g) worst_g = inward, worst = static_cast<int>(it - pinned_.begin());
        continue;
      }
      if (kin_.held[b][i]) continue;
      const bool at_min = x <= specs[i].min + eps && g > kForceTolerance;
      const bool at_max = x >= specs[i].max - eps && g < -kForceTolerance;
      if (!at_min && !at_max) continue;
      blocks_[b][i] = at_min ? specs[i].min : specs[i].max;
      kin_.held[b][i] = true;
      kin_.held_value[b][i] = blocks_[b][i];
      pinned_.push_back({static_cast<int>(b), static_cast<int>(i)});
      ++pinned;
      if (std::getenv("FABATLAS_ASSEMBLY_DEBUG"))
        std::fprintf(stderr, "active set: pin %zu.%zu (%s) at %g, gradient %g\n", b, i, specs[i].name.c_str(),
                     blocks_[b][i], g);
    }
  }
  if (pinned > 0 || worst < 0) return pinned;
  const auto [b, i] = pinned_[worst];
  kin_.held[b][i] = false;
  pinned_.erase(pinned_.begin() + worst);
  if (std::getenv("FABATLAS_ASSEMBLY_DEBUG"))
    std::fprintf(stderr, "active set: unpin %d.%d, pushed in by %g per mm or degree\n", b, i, worst_g);
  return 1;
}

// Gradient of the relaxation energy (gravity, closures, spacing; not the
// gauge anchor) in every parameter, pinned ones included (J per unit).
std::vector<double> Solver::EnergyGradient() {
  for (const auto& [b, i] : pinned_) kin_.held[b][i] = false;
  AssemblyCost cost(Residual(Phase::kRelaxation, opt_.relaxation_penalty));
  std::vector<double> r(cost.num_residuals());
  std::vector<std::vector<double>> jac(blocks_.size(), std::vector<double>(r.size() * internal::kParamBlock));
  std::vector<double*> jp;
  for (auto& j : jac) jp.push_back(j.data());
  const std::vector<double*> x = Pointers();
  cost.Evaluate(x.data(), r.data(), jp.data());
  for (const auto& [b, i] : pinned_) kin_.held[b][i] = true;
  std::vector<double> grad(blocks_.size() * internal::kParamBlock, 0.0);
  for (size_t b = 0; b < blocks_.size(); ++b)
    for (int i = 0; i < internal::kParamBlock; ++i)
      for (size_t k = 0; k < r.size(); ++k)
        grad[internal::kParamBlock * b + i] += jac[b][k * internal::kParamBlock + i] * r[k];
  return grad;
}

}  // namespace fabatlas::assembly::internal
