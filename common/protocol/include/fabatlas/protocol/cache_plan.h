// fabatlas/protocol/cache_plan.h — the geometry cache plan as a task
// (tasks.proto TASK_KIND_CACHE_PLAN; Fab Forms Sec. 6 and 8, docs/cache.md).
//
// One function computes the plan wherever it runs: a cluster worker runs it
// on the input blob of a TASK_KIND_CACHE_PLAN lease, and `fabatlas sample`
// runs it in process (pipeline::LocalExecutor::RunCachePlan), so the artifact of a job is
// the same bytes either way.
#pragma once

#include "fabatlas/cache/optimize_cache.h"
#include "fabatlas/v1/tasks.pb.h"

namespace fabatlas::protocol {

// The plan of docs/cache.md on the input's subtrees:
//  - dependency graph (cache::BuildDependencyGraph) with the deterministic
//    model costs cache::ModelSubtreeSeconds(op, bytes, Σ children's bytes),
//    never measured times (a key's bytes = the largest recorded);
//  - H_TOP, H_opt (options.strategy under options.budget_bytes), H_rfree
//    (OPT-MAX without a budget, run to the end);
//  - the Fig. 13 curve of NAIVE, OPT-AVE and OPT-MAX under the budget;
//  - the entries of H_opt ∪ H_rfree in ascending key order;
//  - when the integer program has at most options.exact_max_variables
//    variables, its worst-case optimum under the budget (GLPK, started from
//    H_opt) and H_opt's gap to it.
// Everything but `exact` is a pure function of the input. Throws InputError
// for unknown strategy or score names and for inconsistent records (a key
// given with different children, a sample root that is no subtree).
v1::CachePlanReport RunCachePlan(const v1::CachePlanInput& input);

// cache::CacheOptions <-> the options message (budget: 0 = none).
v1::CachePlanOptions CachePlanOptionsOf(const cache::CacheOptions& options);
cache::CacheOptions CacheOptionsOf(const v1::CachePlanOptions& options);

}  // namespace fabatlas::protocol
