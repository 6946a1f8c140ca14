// fabatlas/cache/exact_cache.h — the optimal cache of a small graph by integer
// programming (GLPK), to measure how far the greedy strategies are from it.
//
// Variables: h_X ∈ {0,1} for each node that may be chosen (as in
// optimize_cache.h: stored and t >= min_seconds); for each sample r and each
// node X below its root, k_rX >= 0 evaluations of X in r. Constraints:
// k_r,root >= 1 - h_root; k_rX >= Σ_parents mult·k_rp - M_rX·h_X (M_rX = the
// number of paths from r's root to X); Σ bytes_X h_X <= budget; for kWorst
// z >= Σ_X t_X k_rX for every r. Objective: min z (worst preview time) or
// min Σ_r Σ_X t_X k_rX / |R| (mean, Eq. 3).
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "fabatlas/cache/dependency_graph.h"

namespace fabatlas::cache {

enum class ExactObjective { kWorst, kMean };

struct ExactCacheOptions {
  ExactObjective objective = ExactObjective::kWorst;
  std::uint64_t budget_bytes = std::numeric_limits<std::uint64_t>::max();
  double min_seconds = 0.1;        // same meaning as CacheOptions::min_seconds
  double time_limit_seconds = 60;  // branch and bound stops here (not optimal then)
  // Refuse (solved = false) when the program would have more k variables.
  std::int64_t max_variables = 200000;
  // Optional starting solution (e.g. OPT-MAX's CachePlan::cache, within the
  // budget): handed to branch and bound as its first incumbent, so a time
  // limit never returns anything worse. Empty: none.
  CacheSet start;
};

struct ExactCacheSummary {
  bool solved = false;   // a feasible integer solution was found
  bool optimal = false;  // and proven optimal
  CacheSet cache;        // the solution's H (without nodes no sample reaches)
  CacheCost cost;        // EvaluateCache of it
  double objective = 0;  // the program's objective value (s)
  double bound = 0;      // best lower bound on the objective (s)
  std::int64_t variables = 0;
  std::string message;  // why not solved / not optimal
};

ExactCacheSummary SolveExactCache(const DependencyGraph& graph, const ExactCacheOptions& options = {});

}  // namespace fabatlas::cache
