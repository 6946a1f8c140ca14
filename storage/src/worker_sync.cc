// JobStore::SyncWorker: a worker's Sync in one transaction, composed of the
// completions and lease steps (completions.h, leases.h).
#include <mutex>

#include "completions.h"
#include "leases.h"

namespace fabatlas::storage {

using internal::ActiveLease;
using internal::ActiveLeasesOf;
using internal::CompleteIn;
using internal::CountDeltas;
using internal::ExtendIn;
using internal::PickLeases;
using internal::ReturnUnknownIn;
using internal::Transaction;
using internal::WriteLeasesIn;

WorkerSyncOutcome JobStore::SyncWorker(const WorkerSync& sync) {
  WorkerSyncOutcome out;
  std::lock_guard lock(mutex_);
  Transaction t(*db_, Transaction::Deferred{});
  CountDeltas deltas;
  if (!sync.completions.empty()) {
    t.Begin();
    out.outcomes = CompleteIn(*db_, sync.completions, sync.now_ms, sync.retry_backoff_ms, sync.quarantine_after,
                              sync.quarantine_result, deltas);
  }
  // Read after the completions: the leases they ended are no longer active.
  const std::vector<ActiveLease> active = ActiveLeasesOf(*db_, sync.worker_id);
  std::vector<std::string> known = sync.in_flight;
  for (const Completion& c : sync.completions) known.push_back(c.lease_id);
  out.returned = ReturnUnknownIn(*db_, t, active, known, deltas);
  out.revoked =
      ExtendIn(*db_, t, sync.worker_id, active, sync.in_flight, sync.now_ms + sync.lease_ms, sync.lease_ms / 2);
  std::vector<std::int64_t> unprefer;
  out.grants = PickLeases(*db_, sync.worker_id, sync.want, sync.steal, sync.now_ms, sync.lease_ms,
                          preferring_tasks_ > 0, unprefer);
  if (!out.grants.empty()) {
    t.Begin();
    WriteLeasesIn(*db_, sync.worker_id, sync.now_ms, out.grants, unprefer, deltas);
  }
  t.Commit();
  preferring_tasks_ -= static_cast<std::int64_t>(unprefer.size());
  deltas.ApplyTo(counts_);
  return out;
}

}  // namespace fabatlas::storage
