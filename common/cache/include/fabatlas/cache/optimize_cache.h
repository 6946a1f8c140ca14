// fabatlas/cache/optimize_cache.h — choosing the cache H under a memory budget
// (Fab Forms Sec. 6.3, Alg. 1, and the three strategies of Sec. 8, Fig. 13).
//
// Strategies (n = evaluation count, t = root compute time, Sec. 6.2):
//  - kNaive: nodes by largest t·n_∅(X) (counts with no cache), fixed order,
//    no redundancy removal.
//  - kOptAve: repeatedly the node with the largest t·n_H(X) for the current H.
//  - kOptMax (Alg. 1): among the nodes a sample with the largest T_H(r)
//    still evaluates (union over all samples tied at the maximum), the one
//    with the largest t·n_H(X); when those samples evaluate nothing that can
//    be chosen, the kOptAve choice.
// kOptAve and kOptMax drop every node of H that becomes redundant (no sample
// reaches it any more: all the paths to it pass through H) as soon as it does,
// which frees its bytes.
// A node can be chosen when it is stored, t >= min_seconds, n_H > 0, it is
// not in H and it fits in what is left of the budget. Runs stop when nothing
// can be chosen. Ties: lower node id (ascending key) and lower sample index,
// so a plan is a pure function of (graph, options).
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "fabatlas/cache/dependency_graph.h"

namespace fabatlas::cache {

enum class Strategy { kNaive, kOptAve, kOptMax };
const char* StrategyName(Strategy strategy);  // "naive", "opt_ave", "opt_max"

// What the greedy strategies maximise when they choose a node.
enum class Score {
  kTimesCount,    // t·n_H(X), as Fab Forms Sec. 6.3 and Sec. 8 state it
  kPerByte,       // t·n_H(X) / bytes(X)
  kSavedPerByte,  // n_H(X)·C_H(X) / bytes(X), C_H(X) = the time to compute X's
                  // subtree given H: the drop of Σ_r T_H(r) per byte of budget
};

struct CacheOptions {
  Strategy strategy = Strategy::kOptMax;
  Score score = Score::kSavedPerByte;
  // Memory budget for H in bytes (default: unlimited).
  std::uint64_t budget_bytes = std::numeric_limits<std::uint64_t>::max();
  // Subtrees whose root took less than this are never chosen (Fab Forms
  // Sec. 6.1: "otherwise we could just cache the children"). Default 100 ms.
  double min_seconds = 0.1;
  // OPT-MAX only: take the worst samples' best node only when its score is at
  // least this share of the best score overall, else the OPT-AVE choice, so
  // that under a budget the worst case is not bought with a much worse mean
  // (docs/cache.md). 0 = Alg. 1 as published.
  double average_share = 0.9;
  // Record the cost after every step (CachePlan::curve).
  bool record_curve = true;
};

// The cache after one step of a strategy (one node added plus the redundant
// ones dropped). mean/worst as in CacheCost.
struct CurvePoint {
  std::uint64_t bytes = 0;
  std::int64_t entries = 0;
  double mean_seconds = 0.0;
  double worst_seconds = 0.0;
};

struct CachePlan {
  Strategy strategy = Strategy::kOptMax;
  CacheSet cache;                    // H, per node id
  std::vector<std::int32_t> chosen;  // ids in H, ascending
  CacheCost cost;                    // of H, recomputed exactly
  std::vector<CurvePoint> curve;     // curve[0] = empty cache, then each step
  std::int64_t steps = 0;            // nodes added (including later dropped)
  std::int64_t dropped = 0;          // nodes dropped as redundant
};

CachePlan OptimizeCache(const DependencyGraph& graph, const CacheOptions& options = {});

// What Fab Forms Fig. 14 reports for one design, plus the chosen plan.
struct CacheReport {
  CacheCost none;    // empty cache
  CacheCost top;     // H_TOP (TopLevelCache)
  CacheCost rfree;   // H_rfree: OPT-MAX with no budget, run until nothing is left to choose
  CachePlan chosen;  // options.strategy under options.budget_bytes
};

CacheReport PlanCache(const DependencyGraph& graph, const CacheOptions& options = {});

}  // namespace fabatlas::cache
