// The checks of an assembly (FabHacks, 4.3): its cycles close
// (assembly_feasible), it rests stably (assembly_stable) and it reaches its
// target (target_reached).

#include <sstream>

#include "check_kinds.h"
#include "checks.h"
#include "fabatlas/error.h"

namespace fabatlas::design {
namespace check {

// Assemblies (FabHacks, 4.3): the cycles close (pre-checks pass and C below
// the feasibility tolerance).
CheckOutcome AssemblyFeasible(CheckContext& c) {
  const auto a = c.assembly();
  const assembly::SolveSummary& s = a->summary;
  CheckOutcome o;
  o.passed = s.prechecks_passed && s.feasible;
  std::ostringstream reason;
  reason.precision(3);
  if (!o.passed) {
    o.failure = kInfeasible;
    reason << (s.messages.empty() ? std::string("the assembly does not solve") : s.messages.front());
  } else {
    reason << "feasible after " << s.starts_tried << " start" << (s.starts_tried > 1 ? "s" : "")
           << " (C = " << s.constraint_residual << " mm^2)";
  }
  o.reason = reason.str();
  return o;
}

// FabHacks, 4.3.3 step 2: nothing falls apart under gravity and the target
// part moves little during relaxation.
CheckOutcome AssemblyStable(CheckContext& c) {
  const auto a = c.assembly();
  const assembly::SolveSummary& s = a->summary;
  CheckOutcome o;
  o.passed = s.prechecks_passed && s.feasible && s.stable;
  std::ostringstream reason;
  reason.precision(3);
  if (!s.prechecks_passed || !s.feasible) {
    reason << "not solved (infeasible)";
  } else {
    reason << "relaxation moves the target " << s.relax_displacement_mm << " mm, " << s.relax_rotation_deg << " deg";
    for (std::size_t k = 0; k < s.falls_apart.size(); ++k) reason << (k ? ", " : "; falls apart: ") << s.falls_apart[k];
  }
  if (!o.passed) o.failure = kFallsApart;
  o.reason = reason.str();
  o.measures["relax_displacement"] = s.relax_displacement_mm;
  return o;
}

// The relaxed target part within `tolerance` mm (and `tolerance_deg` when the
// program matches rotation) of the end_with pose; measures target_deviation.
CheckOutcome TargetReached(const CheckSpec& spec, CheckContext& c) {
  const double tol = c.Number(spec, "tolerance", 25), tol_deg = c.Number(spec, "tolerance_deg", 10);
  const auto a = c.assembly();
  const assembly::SolveSummary& s = a->summary;
  const bool rotation = a->program.target_match_rotation;
  CheckOutcome o;
  std::ostringstream reason;
  reason.precision(4);
  if (!s.prechecks_passed || !s.feasible) {
    o.failure = kTargetMissed;
    o.reason = "not solved (infeasible)";
    return o;
  }
  o.passed = s.final_target_error_mm <= tol && (!rotation || s.final_target_error_deg <= tol_deg);
  reason << "target deviation " << s.final_target_error_mm << " mm";
  if (rotation) reason << ", " << s.final_target_error_deg << " deg";
  reason << (o.passed ? " (within " : " (exceeds ") << tol << " mm"
         << (rotation ? ", " + std::to_string(tol_deg) + " deg" : "") << ")";
  if (!o.passed) o.failure = kTargetMissed;
  o.reason = reason.str();
  o.measures["target_deviation"] = s.final_target_error_mm;
  if (rotation) o.measures["target_deviation_deg"] = s.final_target_error_deg;
  return o;
}

}  // namespace check

}  // namespace fabatlas::design
