// The coordinator's scheduler (see coordinator_state.h): workers seen, the
// lease sweeper, state-write stalls and blob collection.
#include "coordinator_state.h"
#include "fabatlas/error.h"
#include "fabatlas/log/log.h"

namespace fabatlas::coordinator {

std::set<std::string> restart_drivers;  // jobs whose driver stopped on a state write; under drivers_mu

void Coordinator::Impl::StateWriteFailed(const std::string& where, const std::string& error) {
  ++state_write_failures_total;
  std::int64_t now = NowMs();
  std::lock_guard lock(stall_mu);
  if (!stalled) stall_since_ms = now;
  stalled = true;
  stall_last_ms = now;
  stall_reason = error;
  if (now - stall_logged_ms < 10000) return;
  stall_logged_ms = now;
  log::Error("state_write_failed", {{"where", where},
                                    {"error", error},
                                    {"state_dir", options.state_dir.string()},
                                    {"stalled_ms", now - stall_since_ms}});
}

void Coordinator::Impl::StateWriteSucceeded() {
  if (!stalled) return;
  std::lock_guard lock(stall_mu);
  if (!stalled || NowMs() - stall_last_ms < 5000) return;
  stalled = false;
  stall_logged_ms = 0;
  log::Info("state_write_recovered", {{"stalled_ms", NowMs() - stall_since_ms}});
}

std::string Coordinator::Impl::StallText() {
  if (!stalled) return "";
  std::lock_guard lock(stall_mu);
  return "coordinator cannot write its state for " + std::to_string((NowMs() - stall_since_ms) / 1000) +
         " s: " + stall_reason;
}

void Coordinator::Impl::SignalWork() {
  {
    std::lock_guard lock(work_mu);
    ++work_epoch;
  }
  work_cv.notify_all();
}

void Coordinator::Impl::WorkerAlive(const std::string& id, int slots, std::int64_t now) {
  {
    std::lock_guard lock(workers_mu);
    auto it = workers_seen.find(id);
    if (slots < 0) {
      if (it == workers_seen.end()) return;
      slots = it->second.slots;
    }
    if (it == workers_seen.end()) log::Info("worker_joined", {{"worker", id}, {"slots", slots}});
    workers_seen[id] = {slots, now};
  }
  store->TouchWorker(id, slots, now);
}

std::vector<std::pair<std::string, int>> Coordinator::Impl::ConnectedWorkers() {
  std::vector<std::pair<std::string, int>> out;
  std::int64_t since = NowMs() - options.lease_ms;
  std::lock_guard lock(workers_mu);
  for (const auto& [id, seen] : workers_seen)
    if (seen.slots > 0 && seen.last_ms >= since) out.emplace_back(id, seen.slots);
  return out;
}

void Coordinator::Impl::CollectBlobs(const std::string& reason) {
  std::lock_guard lock(collect_mu);
  std::int64_t cutoff = NowMs() - 10000;
  const std::int64_t oldest_lease = store->OldestActiveLeaseMs();
  if (oldest_lease >= 0) cutoff = std::min(cutoff, oldest_lease - 1000);
  const std::vector<std::string> keep = store->ReferencedBlobs();
  // The store a power loss could roll back to must not name a blob swept
  // now (a job's end drops its geometry references; rolled back, the job
  // replays and needs them): what `keep` was read from is made durable
  // before the first blob goes.
  const storage::BlobStore::Collection c = blobs->Collect(keep, cutoff, [this] { store->Sync(); });
  blobs_collected_total += c.blobs_removed;
  blob_bytes_collected_total += c.bytes_removed;
  if (c.blobs_removed > 0)
    log::Info("blobs_collected", {{"reason", reason},
                                  {"removed", c.blobs_removed},
                                  {"removed_bytes", c.bytes_removed},
                                  {"kept", c.blobs_kept},
                                  {"kept_bytes", c.bytes_kept}});
}

void Coordinator::Impl::CheckpointAndRestartDrivers() {
  // A checkpoint copies every WAL frame since the last one that
  // completed, all or nothing (SQLite, "Write-Ahead Logging"): on a
  // disk that fails one write in n, a backlog past n frames never
  // completes. Its failure must not hold up what follows: the stopped
  // drivers' restarts and the lease sweep (they once waited for a
  // checkpoint to succeed, and a fault on every 25th store write
  // starved the job).
  try {
    store->Checkpoint();
    StateWriteSucceeded();
  } catch (const ResourceError& e) {
    StateWriteFailed("checkpoint", e.what());
  }
  std::set<std::string> restart;
  {
    std::lock_guard lock(drivers_mu);
    restart.swap(restart_drivers);
  }
  for (const auto& id : restart) StartDriver(id);
}

std::vector<storage::ExpiredLease> Coordinator::Impl::ExpireOverdueLeases(std::int64_t now, bool& expiry_held) {
  // While the store cannot be written no lease expires: a worker's
  // heartbeats and reports fail with the coordinator's own writes, so a
  // lease past its deadline says nothing of its worker (expiring it
  // fenced results on their way, and with a fault on every 25th store
  // write the same tasks were leased again and again). One lease period
  // after the last failed write, the leases get one period of grace, as
  // after a restart, then expire as usual: a worker that died meanwhile
  // is noticed then.
  std::int64_t last_failure_ms = 0;
  {
    std::lock_guard lock(stall_mu);
    last_failure_ms = stall_last_ms;
  }
  const bool hold = last_failure_ms > 0 && now - last_failure_ms < options.lease_ms;
  if (hold) {
    expiry_held = true;
  } else if (expiry_held) {
    store->ExtendAllLeases(now + options.lease_ms);
    expiry_held = false;
  }
  std::vector<storage::ExpiredLease> expired;
  if (!hold) expired = store->ExpireLeases(now, options.retry_backoff_ms, options.quarantine_after, QuarantineBytes);
  for (const auto& e : expired) {
    log::Warn("lease_expired", {{"task", e.task_key},
                                {"job", e.job_id},
                                {"worker", e.worker_id},
                                {"attempt", e.attempt},
                                {"expiries", e.expiries}});
    if (!e.quarantined) continue;
    log::Error("task_quarantined", {{"task", e.task_key}, {"job", e.job_id}, {"expiries", e.expiries}});
    if (auto task = store->FindTask(e.task_key)) Deliver(e.task_key, task->result);
  }
  return expired;
}

void Coordinator::Impl::ForgetSilentWorkers(std::int64_t now) {
  std::vector<std::string> silent;
  {
    std::lock_guard lock(workers_mu);
    for (auto it = workers_seen.begin(); it != workers_seen.end();)
      if (it->second.last_ms < now - options.lease_ms) {
        log::Warn("worker_lost", {{"worker", it->first}, {"silent_ms", now - it->second.last_ms}});
        silent.push_back(it->first);
        it = workers_seen.erase(it);
      } else {
        ++it;
      }
  }
  for (const auto& id : silent)
    if (store->ForgetAffinity(id) > 0) SignalWork();
  if (silent.empty()) return;
  // Requests a silent holder will never answer: answered "not held".
  std::lock_guard lock(share_mu);
  for (const auto& id : silent) {
    for (const auto& ref : share_wanted[id]) shares[SolidKey(ref)].answered = true;
    share_wanted.erase(id);
    share_polled.erase(id);
  }
  share_cv.notify_all();
}

void Coordinator::Impl::Sweep() {
  std::int64_t last_checkpoint_ms = NowMs(), last_collect_ms = 0;
  bool expiry_held = false;  // leases were kept past their deadlines while writes failed
  while (!stopping) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    try {
      std::int64_t now = NowMs();
      if (now - last_checkpoint_ms >= 1000) {
        last_checkpoint_ms = now;
        CheckpointAndRestartDrivers();
      }
      const std::vector<storage::ExpiredLease> expired = ExpireOverdueLeases(now, expiry_held);
      if (!expired.empty()) last_retry_ms = now;
      ForgetSilentWorkers(now);
      if (now - last_collect_ms >= 10000) {
        CollectBlobs("periodic");
        last_collect_ms = now;
      }
      if (!expired.empty() || now - last_retry_ms < 31000) SignalWork();
    } catch (const ResourceError& e) {
      StateWriteFailed("sweep", e.what());
    } catch (const std::exception& e) {
      log::Error("sweep_failed", {{"error", e.what()}});
    }
  }
}

}  // namespace fabatlas::coordinator
