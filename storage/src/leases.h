// The job store's leases inside a caller's transaction: which tasks a
// worker gets (lease affinity, worker.proto), the lease rows, returns and
// extensions (internal to storage/; JobStore's lease methods and SyncWorker
// compose them).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fabatlas/sqlite/connection.h"
#include "fabatlas/storage/job_store.h"
#include "task_counts.h"
#include "transaction.h"

namespace fabatlas::storage::internal {

// GrantLeases' choice of tasks, by reads only (so an empty queue costs no
// write transaction): up to `max` grants, of them up to `steal` preferring
// other workers (all when negative); unprefer gets the seq of granted tasks
// that had a preference. any_preferring: some task prefers a worker.
std::vector<LeaseGrant> PickLeases(sqlite::Connection& db, const std::string& worker_id, int max, int steal,
                                   std::int64_t now_ms, std::int64_t lease_ms, bool any_preferring,
                                   std::vector<std::int64_t>& unprefer);

// Writes picked grants (PickLeases) inside the caller's transaction (begun):
// tasks leased, lease rows, preferences of the granted tasks dropped.
void WriteLeasesIn(sqlite::Connection& db, const std::string& worker_id, std::int64_t now_ms,
                   const std::vector<LeaseGrant>& grants, const std::vector<std::int64_t>& unprefer,
                   CountDeltas& deltas);

// A worker's active lease.
struct ActiveLease {
  std::string lease_id, task_key, job_id;
  std::int64_t deadline_ms = 0;
};

// The worker's active leases (one read, shared by ReturnUnknownIn and
// ExtendIn).
std::vector<ActiveLease> ActiveLeasesOf(sqlite::Connection& db, const std::string& worker_id);

// ReturnUnknownLeases: the active leases not in `known` go back to the
// queue, inside `t` (begun when there is one). Returns how many.
int ReturnUnknownIn(sqlite::Connection& db, Transaction& t, const std::vector<ActiveLease>& active,
                    const std::vector<std::string>& known, CountDeltas& deltas);

// ExtendLeases inside `t` (begun only when a deadline moves): the listed
// ids that are active leases due before deadline_ms - slack_ms move to
// deadline_ms; returns the listed ids that are not active leases.
std::vector<std::string> ExtendIn(sqlite::Connection& db, Transaction& t, const std::string& worker_id,
                                  const std::vector<ActiveLease>& active, const std::vector<std::string>& lease_ids,
                                  std::int64_t deadline_ms, std::int64_t slack_ms);

}  // namespace fabatlas::storage::internal
