// The job store's completions inside a caller's transaction (internal to
// storage/; JobStore::Complete and SyncWorker use it).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "fabatlas/sqlite/connection.h"
#include "fabatlas/storage/job_store.h"
#include "task_counts.h"

namespace fabatlas::storage::internal {

// JobStore::Complete's work inside the caller's transaction (begun):
// outcomes in input order, count changes into `deltas`.
std::vector<CompletionOutcome> CompleteIn(sqlite::Connection& db, const std::vector<Completion>& completions,
                                          std::int64_t now_ms, std::int64_t retry_backoff_ms, int quarantine_after,
                                          const std::function<std::string(int kind)>& quarantine_result,
                                          CountDeltas& deltas);

}  // namespace fabatlas::storage::internal
