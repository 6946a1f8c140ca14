// The job store's leases: grants (lease affinity), returns, extensions,
// expiries and affinity (see leases.h and job_store.h).
#include "leases.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <mutex>
#include <set>

namespace fabatlas::storage {
namespace internal {

namespace {

// A lease's id: the task's seq as 16 hex digits, then the attempt. Ids in
// the order leases are granted put each new row of the leases primary key
// index beside the last one (an id from the task key's first digits, as
// before, landed on a random page of it, one more WAL page per grant).
// Unique per store, as the seq is; opaque to
// workers, so ids of the earlier form in a store still work.
std::string LeaseIdOf(std::int64_t task_seq, std::int64_t attempt) {
  char seq[17];
  std::snprintf(seq, sizeof seq, "%016llx", static_cast<unsigned long long>(task_seq));
  return std::string(seq) + "." + std::to_string(attempt);
}

}  // namespace

std::vector<LeaseGrant> PickLeases(sqlite::Connection& db, const std::string& worker_id, int max, int steal,
                                   std::int64_t now_ms, std::int64_t lease_ms, bool any_preferring,
                                   std::vector<std::int64_t>& unprefer) {
  std::vector<LeaseGrant> grants;
  if (max <= 0) return grants;
  // Lease affinity
  // (worker.proto): this worker's preferred tasks, then tasks preferring
  // nobody, then other workers' preferred tasks from the newest.
  constexpr const char* kColumns =
      "SELECT t.key, t.job_id, j.bundle_digest, t.attempt, t.kind, t.payload, t.seq, t.affine FROM ";
  static const std::string own = std::string(kColumns) +
                                 "task_affinity a JOIN tasks t ON t.seq = a.task_seq JOIN jobs j ON j.id = t.job_id "
                                 "WHERE a.worker_id = ? AND t.state = 0 AND j.state = 2 AND t.not_before_ms <= ? "
                                 "ORDER BY a.rank, a.task_seq LIMIT ?";
  static const std::string neutral = std::string(kColumns) +
                                     "tasks t JOIN jobs j ON j.id = t.job_id WHERE t.state = 0 AND t.affine = 0 AND "
                                     "j.state = 2 AND t.not_before_ms <= ? ORDER BY t.seq LIMIT ?";
  static const std::string others = std::string(kColumns) +
                                    "tasks t JOIN jobs j ON j.id = t.job_id WHERE t.state = 0 AND t.affine = 1 AND "
                                    "j.state = 2 AND t.not_before_ms <= ? ORDER BY t.seq DESC LIMIT ?";
  std::set<std::int64_t> picked;
  auto take = [&](sqlite::Statement& pick, int cap) {  // until `cap` grants in all
    while (static_cast<int>(grants.size()) < cap && pick.Next()) {
      std::int64_t seq = pick.ColumnInt(6);
      if (!picked.insert(seq).second) continue;
      if (pick.ColumnInt(7) != 0) unprefer.push_back(seq);
      LeaseGrant g;
      g.task_key = pick.ColumnText(0);
      g.job_id = pick.ColumnText(1);
      g.bundle_digest = pick.ColumnText(2);
      g.attempt = pick.ColumnInt(3) + 1;
      g.kind = static_cast<int>(pick.ColumnInt(4));
      g.payload = pick.ColumnText(5);
      g.lease_id = LeaseIdOf(seq, g.attempt);
      g.deadline_ms = now_ms + lease_ms;
      grants.push_back(std::move(g));
    }
  };
  if (any_preferring) {  // skipped while no task prefers anyone (no-op jobs)
    auto pick = db.Cached(own);
    pick.BindText(1, worker_id).Bind(2, now_ms).Bind(3, std::int64_t{max});
    take(pick, max);
  }
  if (static_cast<int>(grants.size()) < max) {
    auto pick = db.Cached(neutral);
    pick.Bind(1, now_ms).Bind(2, std::int64_t{max - static_cast<int>(grants.size())});
    take(pick, max);
  }
  // Never skipped while the worker has an idle slot: no preferred task can
  // starve. Own preferred tasks were all taken above and may come again here.
  const int before = static_cast<int>(grants.size());
  const int limit = steal < 0 ? max : std::min(max, before + steal);
  if (before < limit) {
    auto pick = db.Cached(others);
    pick.Bind(1, now_ms).Bind(2, std::int64_t{limit - before + static_cast<int>(unprefer.size())});
    take(pick, limit);
  }
  return grants;
}

void WriteLeasesIn(sqlite::Connection& db, const std::string& worker_id, std::int64_t now_ms,
                   const std::vector<LeaseGrant>& grants, const std::vector<std::int64_t>& unprefer,
                   CountDeltas& deltas) {
  auto update = db.Cached("UPDATE tasks SET state = 1, attempt = ? WHERE key = ?");
  auto lease = db.Cached(
      "INSERT OR REPLACE INTO leases (lease_id, task_key, attempt, worker_id, granted_ms, "
      "deadline_ms, state) VALUES (?,?,?,?,?,?,'active')");
  for (const LeaseGrant& g : grants) {
    update.Bind(1, g.attempt).BindText(2, g.task_key);
    update.Run();
    update.Reset();
    deltas.Moved(g.job_id, TaskState::kQueued, TaskState::kLeased);
    lease.BindText(1, g.lease_id).BindText(2, g.task_key).Bind(3, g.attempt).BindText(4, worker_id);
    lease.Bind(5, now_ms).Bind(6, g.deadline_ms);
    lease.Run();
    lease.Reset();
  }
  if (!unprefer.empty()) {
    auto drop = db.Cached("DELETE FROM task_affinity WHERE task_seq = ?");
    auto neutral_again = db.Cached("UPDATE tasks SET affine = 0 WHERE seq = ?");
    for (std::int64_t seq : unprefer) {
      drop.Bind(1, seq);
      drop.Run();
      drop.Reset();
      neutral_again.Bind(1, seq);
      neutral_again.Run();
      neutral_again.Reset();
    }
  }
  // The worker's last_seen_ms is not written here: TouchWorker keeps it (to
  // 1 s) on every Sync and Heartbeat, and a write per grant put the workers
  // page into nearly every commit's WAL frames.
}

std::vector<ActiveLease> ActiveLeasesOf(sqlite::Connection& db, const std::string& worker_id) {
  auto s = db.Cached(
      "SELECT l.lease_id, l.task_key, t.job_id, l.deadline_ms FROM leases l JOIN tasks t ON t.key = l.task_key "
      "WHERE l.worker_id = ? AND l.state = 'active'");
  s.BindText(1, worker_id);
  return s.Rows([](const sqlite::Statement& row) {
    return ActiveLease{row.ColumnText(0), row.ColumnText(1), row.ColumnText(2), row.ColumnInt(3)};
  });
}

int ReturnUnknownIn(sqlite::Connection& db, Transaction& t, const std::vector<ActiveLease>& active,
                    const std::vector<std::string>& known, CountDeltas& deltas) {
  std::set<std::string> keep(known.begin(), known.end());
  int returned = 0;
  for (const ActiveLease& l : active) {
    if (keep.count(l.lease_id)) continue;
    t.Begin();
    auto lease = db.Cached("UPDATE leases SET state = 'returned' WHERE lease_id = ?");
    lease.BindText(1, l.lease_id);
    lease.Run();
    auto task = db.Cached("UPDATE tasks SET state = 0 WHERE key = ? AND state = 1");
    task.BindText(1, l.task_key);
    task.Run();
    if (sqlite3_changes(db.get()) == 1) deltas.Moved(l.job_id, TaskState::kLeased, TaskState::kQueued);
    ++returned;
  }
  return returned;
}

std::vector<std::string> ExtendIn(sqlite::Connection& db, Transaction& t, const std::string& worker_id,
                                  const std::vector<ActiveLease>& active, const std::vector<std::string>& lease_ids,
                                  std::int64_t deadline_ms, std::int64_t slack_ms) {
  std::map<std::string, std::int64_t> deadlines;
  for (const ActiveLease& l : active) deadlines.emplace(l.lease_id, l.deadline_ms);
  std::vector<std::string> revoked;
  for (const std::string& id : lease_ids) {
    auto it = deadlines.find(id);
    if (it == deadlines.end()) {
      revoked.push_back(id);
      continue;
    }
    if (it->second >= deadline_ms - slack_ms) continue;
    t.Begin();
    auto s = db.Cached(
        "UPDATE leases SET deadline_ms = MAX(deadline_ms, ?) WHERE lease_id = ? AND worker_id = ? "
        "AND state = 'active'");
    s.Bind(1, deadline_ms).BindText(2, id).BindText(3, worker_id);
    s.Run();
  }
  return revoked;
}

}  // namespace internal

using internal::ActiveLeasesOf;
using internal::CountDeltas;
using internal::ExtendIn;
using internal::kSampleKind;
using internal::PickLeases;
using internal::ReturnUnknownIn;
using internal::Transaction;
using internal::WriteLeasesIn;

std::vector<LeaseGrant> JobStore::GrantLeases(const std::string& worker_id, int max, std::int64_t now_ms,
                                              std::int64_t lease_ms, int steal) {
  std::lock_guard lock(mutex_);
  std::vector<std::int64_t> unprefer;
  std::vector<LeaseGrant> grants =
      PickLeases(*db_, worker_id, max, steal, now_ms, lease_ms, preferring_tasks_ > 0, unprefer);
  if (grants.empty()) return grants;
  Transaction t(*db_);
  CountDeltas deltas;
  WriteLeasesIn(*db_, worker_id, now_ms, grants, unprefer, deltas);
  t.Commit();
  preferring_tasks_ -= static_cast<std::int64_t>(unprefer.size());
  deltas.ApplyTo(counts_);
  return grants;
}

int JobStore::ForgetAffinity(const std::string& worker_id) {
  std::lock_guard lock(mutex_);
  std::vector<std::int64_t> seqs;
  {
    auto s = db_->Cached("SELECT task_seq FROM task_affinity WHERE worker_id = ?");
    s.BindText(1, worker_id);
    while (s.Next()) seqs.push_back(s.ColumnInt(0));
  }
  if (seqs.empty()) return 0;
  Transaction t(*db_);
  auto drop = db_->Cached("DELETE FROM task_affinity WHERE worker_id = ?");
  drop.BindText(1, worker_id);
  drop.Run();
  auto neutral_again = db_->Cached(
      "UPDATE tasks SET affine = 0 WHERE seq = ? AND affine = 1 AND NOT EXISTS (SELECT 1 FROM task_affinity a "
      "WHERE a.task_seq = ?)");
  int lost = 0;
  for (std::int64_t seq : seqs) {
    neutral_again.Bind(1, seq).Bind(2, seq);
    neutral_again.Run();
    lost += sqlite3_changes(db_->get());
    neutral_again.Reset();
  }
  t.Commit();
  preferring_tasks_ -= lost;
  return lost;
}

void JobStore::ClearAffinity() {
  std::lock_guard lock(mutex_);
  Transaction t(*db_);
  db_->Exec("DELETE FROM task_affinity");
  db_->Exec("UPDATE tasks SET affine = 0 WHERE affine != 0");
  t.Commit();
  preferring_tasks_ = 0;
}

std::vector<std::string> JobStore::ExtendLeases(const std::string& worker_id, const std::vector<std::string>& lease_ids,
                                                std::int64_t deadline_ms, std::int64_t slack_ms) {
  if (lease_ids.empty()) return {};
  std::lock_guard lock(mutex_);
  // Read first: a Sync that lists leases extended moments ago writes nothing.
  Transaction t(*db_, Transaction::Deferred{});
  auto revoked = ExtendIn(*db_, t, worker_id, ActiveLeasesOf(*db_, worker_id), lease_ids, deadline_ms, slack_ms);
  t.Commit();
  return revoked;
}

int JobStore::ReturnUnknownLeases(const std::string& worker_id, const std::vector<std::string>& known) {
  std::lock_guard lock(mutex_);
  Transaction t(*db_, Transaction::Deferred{});
  CountDeltas deltas;
  const int returned = ReturnUnknownIn(*db_, t, ActiveLeasesOf(*db_, worker_id), known, deltas);
  t.Commit();
  deltas.ApplyTo(counts_);
  return returned;
}

std::vector<ExpiredLease> JobStore::ExpireLeases(std::int64_t now_ms, std::int64_t backoff_ms, int quarantine_after,
                                                 const std::function<std::string(int kind)>& quarantine_result) {
  std::vector<ExpiredLease> expired;
  std::lock_guard lock(mutex_);
  std::vector<std::int64_t> kinds, expiries;
  {
    auto s = db_->Cached(
        "SELECT l.lease_id, l.task_key, t.job_id, l.worker_id, t.kind, t.expiries, l.attempt FROM leases l "
        "JOIN tasks t ON t.key = l.task_key WHERE l.state = 'active' AND l.deadline_ms < ?");
    s.Bind(1, now_ms);
    while (s.Next()) {
      ExpiredLease e;
      e.lease_id = s.ColumnText(0);
      e.task_key = s.ColumnText(1);
      e.job_id = s.ColumnText(2);
      e.worker_id = s.ColumnText(3);
      kinds.push_back(s.ColumnInt(4));
      expiries.push_back(s.ColumnInt(5) + 1);
      e.expiries = expiries.back();
      e.attempt = s.ColumnInt(6);
      expired.push_back(std::move(e));
    }
  }
  if (expired.empty()) return expired;
  Transaction t(*db_);
  auto lease = db_->Cached("UPDATE leases SET state = 'expired' WHERE lease_id = ?");
  auto requeue = db_->Cached(
      "UPDATE tasks SET state = 0, expiries = ?, not_before_ms = ? WHERE key = ? AND "
      "state = 1");
  auto quarantine = db_->Cached(
      "UPDATE tasks SET state = 3, expiries = ?, result = ?, completions = "
      "completions + 1, sample_valid = CASE WHEN kind = 1 THEN 0 ELSE -1 END "
      "WHERE key = ? AND state = 1");
  auto event = db_->Cached("INSERT INTO events (time_ms, job_id, kind, message) VALUES (?,?,?,?)");
  CountDeltas deltas;
  for (std::size_t i = 0; i < expired.size(); ++i) {
    ExpiredLease& e = expired[i];
    lease.BindText(1, e.lease_id);
    lease.Run();
    lease.Reset();
    std::string kind = "lease_expired";
    if (expiries[i] >= quarantine_after) {
      e.quarantined = true;
      kind = "quarantined";
      quarantine.Bind(1, expiries[i]).Bind(2, quarantine_result(static_cast<int>(kinds[i])));
      quarantine.BindText(3, e.task_key);
      quarantine.Run();
      quarantine.Reset();
      if (sqlite3_changes(db_->get()) == 1) {
        deltas.Moved(e.job_id, TaskState::kLeased, TaskState::kQuarantined);
        deltas.Expired(e.job_id);
        if (kinds[i] == kSampleKind) deltas.Sampled(e.job_id, false);
      }
    } else {
      std::int64_t delay = backoff_ms << std::min<std::int64_t>(expiries[i] - 1, 20);
      delay = std::min<std::int64_t>(delay, 30000);
      requeue.Bind(1, expiries[i]).Bind(2, now_ms + delay).BindText(3, e.task_key);
      requeue.Run();
      requeue.Reset();
      if (sqlite3_changes(db_->get()) == 1) {
        deltas.Moved(e.job_id, TaskState::kLeased, TaskState::kQueued);
        deltas.Expired(e.job_id);
      }
    }
    event.Bind(1, now_ms).BindText(2, e.job_id).BindText(3, kind);
    event.BindText(4, "task " + e.task_key.substr(0, 16) + " lease " + e.lease_id + " of worker " + e.worker_id +
                          " expired (" + std::to_string(expiries[i]) + " so far)");
    event.Run();
    event.Reset();
  }
  t.Commit();
  deltas.ApplyTo(counts_);
  return expired;
}

void JobStore::ExtendAllLeases(std::int64_t deadline_ms) {
  std::lock_guard lock(mutex_);
  auto s = db_->Cached("UPDATE leases SET deadline_ms = MAX(deadline_ms, ?) WHERE state = 'active'");
  s.Bind(1, deadline_ms);
  s.Run();
}

std::int64_t JobStore::ActiveLeases() {
  std::lock_guard lock(mutex_);
  auto s = db_->Cached("SELECT COUNT(*) FROM leases WHERE state = 'active'");
  s.Next();
  return s.ColumnInt(0);
}

std::int64_t JobStore::OldestActiveLeaseMs() {
  std::lock_guard lock(mutex_);
  auto s = db_->Cached("SELECT MIN(granted_ms) FROM leases WHERE state = 'active'");
  if (!s.Next() || s.ColumnIsNull(0)) return -1;
  return s.ColumnInt(0);
}

}  // namespace fabatlas::storage
