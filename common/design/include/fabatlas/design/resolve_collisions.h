// fabatlas/design/resolve_collisions.h — automatic collision resolution of a
// reconfigurable design (Reconfigurables, Sec. 6.6).
//
// Minimises the energy of Eq. 1, the area of the spacetime intersection
// surface summed over every pair of objects and transition, over the
// design's degrees of freedom (its exposed real parameters, each within its
// range) by gradient descent: greedily, each step takes the pair that
// contributes most to the energy, follows its hint (resolution_hint.h, Eq.
// 3, scaled to each parameter's range and projected on the bounds) and
// chooses the step length by golden-section search (Press et al. 1992) on
// the energy of all pairs. A flat stretch of the energy above zero means the
// contour has not left yet (the search goes on past it); zero means resolved
// (the search closes in on the smallest such step).
//
// The result is proved with the check precompute uses: the design is
// evaluated at the resolved point with every check (EvaluateSample), and
// `resolved` is its verdict. When the energy is zero but a check still
// fails (a clearance requirement, a contact between two time samples), the
// step is extended along the last direction (ResolutionOptions::
// max_extra_steps).
//
// Threading: the calling thread. Cost: about (parameters + line-search
// iterations) design evaluations per step.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "fabatlas/design/resolution_hint.h"

namespace fabatlas::design {

struct ResolveStep {
  std::string object_a, object_b;  // the pair resolved
  double energy_before = 0, energy_after = 0;
  std::map<std::string, double> edit;  // parameter changes of this step
};

struct ResolveSummary {
  bool resolved = false;  // every check passes at `after`
  Point before, after;
  std::map<std::string, double> edit;  // after - before, the parameters that changed
  // |edit| with each parameter over its range (0..sqrt(parameters)).
  double edit_size = 0;
  double energy_before = 0, energy_after = 0;
  std::string failure_before, failure_after;  // empty when valid
  std::string reason_after;                   // the failed check's reason, when not resolved
  std::vector<ResolveStep> steps;
  int evaluations = 0;
  double seconds = 0;
};

// Throws as ResolutionHints does.
ResolveSummary ResolveCollisions(const Design& design, const Point& u, const ResolutionOptions& options = {});

}  // namespace fabatlas::design
