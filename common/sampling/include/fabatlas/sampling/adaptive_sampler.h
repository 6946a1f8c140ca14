// fabatlas/sampling/adaptive_sampler.h — adaptive sampling of a design space
// (Fab Forms, Sec. 5.2; docs/sampling.md).
//
// 1. Bootstrap: evaluate every vertex of the uniform grid (DesignSpace).
// 2. Rounds, breadth-first: the frontier is every leaf at the current depth.
//    a. ΔG on every edge of every frontier leaf not already known (invalid /
//       invalid = 0, valid / invalid = 1, valid / valid from the evaluator,
//       as one batch of GeometryChangeTasks).
//    b. Per leaf, in tree order: stop if depth == max_depth or the max ΔG <
//       dg_threshold; otherwise for every direction d, s(d) = ΔG of the
//       2^(n-1) edges along d sorted descending; directions ranked by s
//       compared lexicographically (larger first, ties to the lower
//       dimension index); split at the midpoint of the best direction that
//       can still be split and has s(d)[0] >= dg_threshold (a discrete
//       dimension whose values are adjacent hands over to the next-ranked).
//    c. Budget: split candidates are accepted in order of decreasing score
//       (max ΔG, then s vector of the chosen direction, then tree order)
//       while samples + new samples <= max_samples; the first candidate that
//       does not fit ends refinement everywhere (its and later leaves stop
//       with LeafStop::kBudget). The bootstrap grid is always evaluated.
//    d. The new samples (where the split planes cut the edges) are evaluated
//       as one batch of SampleTasks; ids follow ascending key order.
// The result depends only on the evaluator's outcomes, never on thread count
// or completion order.
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "fabatlas/sampling/design_space.h"
#include "fabatlas/sampling/executor.h"
#include "fabatlas/sampling/form.h"
#include "fabatlas/sampling/sample_evaluator.h"

namespace fabatlas::sampling {

struct SamplingOptions {
  int max_depth = 6;                  // splits below a bootstrap cell
  double dg_threshold = 0.1;          // stop when max ΔG in a leaf < this
  std::int64_t max_samples = 100000;  // global budget (bootstrap always done)
};

// Fab Forms Table 3 statistics plus sampler bookkeeping.
struct SamplingStatistics {
  std::int64_t samples = 0;
  std::int64_t valid_samples = 0;
  std::int64_t geometry_changes = 0;       // ΔG values stored
  std::int64_t geometry_change_calls = 0;  // of which computed by the evaluator
  std::int64_t leaves = 0;
  std::map<LeafStop, std::int64_t> leaf_stops;
  // Sum of thread CPU time in EvaluateSample and GeometryChange calls.
  double evaluator_cpu_seconds = 0.0;
  // Sum of wall time in evaluator calls (over all threads).
  double evaluator_wall_seconds = 0.0;
  // Wall time of SampleDesignSpace, and the part spent outside executor
  // batches (tree bookkeeping, split selection: pure sampling logic).
  double wall_seconds = 0.0;
  double sampling_logic_seconds = 0.0;
  // Volume of all-valid leaves / volume of the bounded space, in percent
  // (Fab Forms Sec. 8 "Valid Region Analysis"); discrete dimensions measured
  // in value steps (DesignSpace::length).
  double valid_volume_percent = 0.0;
  // Failure type -> share of invalid samples (sums to 1 if any invalid).
  std::map<std::string, double> failure_shares;
};

struct SamplingSummary {
  Form form;
  SamplingStatistics statistics;
};

// Throws fabatlas::InputError for options out of range (max_depth < 0 or
// > 4 * kDyadicBits, dg_threshold outside [0, 1], max_samples < 1).
SamplingSummary SampleDesignSpace(const DesignSpace& space, SampleEvaluator& evaluator, Executor& executor,
                                  const SamplingOptions& options);

// Valid-volume % of a form (as in SamplingStatistics).
double ValidVolumePercent(const Form& form);

}  // namespace fabatlas::sampling
