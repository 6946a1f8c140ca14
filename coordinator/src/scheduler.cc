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
  log::Error("state_write_failed", {{"where", where}, {"error", error}, {"state_dir", options.state_dir.string()},
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
    log::Info("blobs_collected", {{"reason", reason}, {"removed", c.blobs_removed},
                                  {"removed_bytes", c.bytes_removed}, {"kept", c.blobs_kept},
                                  {"kept_bytes", c.bytes_kept}});
}

void Coordinator::Impl::Sweep() {
  std::int64_t last_checkpoint_ms = NowMs(), last_collect_ms = 0;
  while (!stopping) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    try {
      std::int64_t now = NowMs();
      if (now - last_checkpoint_ms >= 1000) {
        last_checkpoint_ms = now;
        store->Checkpoint();
        StateWriteSucceeded();
        std::set<std::string> restart;
        {
          std::lock_guard lock(drivers_mu);
          restart.swap(restart_drivers);
        }
        for (const auto& id : restart) StartDriver(id);
      }
      auto expired = store->ExpireLeases(now, options.retry_backoff_ms, options.quarantine_after, QuarantineBytes);
      for (const auto& e : expired) {
        log::Warn("lease_expired", {{"task", e.task_key}, {"job", e.job_id}, {"worker", e.worker_id},
                                    {"attempt", e.attempt}, {"expiries", e.expiries}});
        if (!e.quarantined) continue;
        log::Error("task_quarantined", {{"task", e.task_key}, {"job", e.job_id}, {"expiries", e.expiries}});
        if (auto task = store->FindTask(e.task_key)) Deliver(e.task_key, task->result);
      }
      if (!expired.empty()) last_retry_ms = now;
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
      if (!silent.empty()) {
        // Requests a silent holder will never answer: answered "not held".
        std::lock_guard lock(share_mu);
        for (const auto& id : silent) {
          for (const auto& ref : share_wanted[id]) shares[SolidKey(ref)].answered = true;
          share_wanted.erase(id);
          share_polled.erase(id);
        }
        share_cv.notify_all();
      }
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
