// fabatlas/pipeline/cache_options.h — the job file's `cache:` section
// (docs/job-format.md):
//   cache:
//     strategy: opt_max     # naive | opt_ave | opt_max
//     budget_mb: 512        # memory budget of H_opt (default: kDefaultCacheBudgetMb)
//     min_subtree_seconds: 0.1  # subtrees whose model root cost (docs/cache.md)
//                               # is lower are never cached; cluster workers
//                               # also upload only subtrees this slow
//     store_rfree: false    # also store H_rfree beyond H_opt (StoresRfree)
#pragma once

#include <cstdint>

#include "fabatlas/cache/optimize_cache.h"
#include "fabatlas/sampling/job_file.h"

namespace fabatlas::pipeline {

// H_opt's memory budget when the job file gives no cache.budget_mb, in MiB
// of level-set memory (design::SubtreeRecord::bytes). A viewer holds H_opt
// in memory, so this bounds `fabatlas serve` and the artifact's size.
inline constexpr std::uint64_t kDefaultCacheBudgetMb = 256;

// The section's strategy, budget and threshold. Throws InputError
// "<job file>: cache: ..." for unknown keys or bad values.
cache::CacheOptions CacheOptionsOf(const sampling::JobFile& job);
// cache.store_rfree of the job file (default false); same errors.
bool StoresRfree(const sampling::JobFile& job);
// Whether a job asks for a geometry cache: its job file has a `cache:`
// section with a strategy or budget (`min_subtree_seconds` alone only sets
// what workers upload).
bool WantsCache(const sampling::JobFile& job);

}  // namespace fabatlas::pipeline
