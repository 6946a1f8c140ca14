// The job store's completions: results accepted, duplicates and fenced
// results acknowledged, failures requeued or quarantined, a sample's
// subtrees recorded (see completions.h and job_store.h).
#include "completions.h"

#include <algorithm>
#include <mutex>

#include "fabatlas/key_list_text.h"
#include "transaction.h"

namespace fabatlas::storage {
namespace internal {

namespace {

// The statements of one CompleteIn call, from the connection's cache.
struct CompletionStatements {
  explicit CompletionStatements(sqlite::Connection& db) : db(db) {}
  sqlite::Connection& db;
  sqlite::Statement task = db.Cached("SELECT state, attempt, job_id, kind FROM tasks WHERE key = ?");
  sqlite::Statement lease = db.Cached("SELECT state FROM leases WHERE lease_id = ? AND task_key = ? AND attempt = ?");
  sqlite::Statement subtree = db.Cached(
      "INSERT INTO subtrees (job_id, key, topology, op, digest, bytes, children, seconds_sum, "
      "seconds_count, last_seconds, uses) VALUES (?,?,?,?,?,?,?,?,?,?,1) "
      "ON CONFLICT (job_id, key) DO UPDATE SET "
      "digest = CASE WHEN digest = '' THEN excluded.digest ELSE digest END, "
      "seconds_sum = seconds_sum + excluded.seconds_sum, "
      "seconds_count = seconds_count + excluded.seconds_count, "
      "last_seconds = excluded.last_seconds, uses = uses + 1");
  sqlite::Statement use = db.Cached(
      "INSERT OR IGNORE INTO sample_subtrees (task_key, position, job_id, point_key, subtree_key) "
      "VALUES (?,?,?,?,?)");
  sqlite::Statement set_lease = db.Cached("UPDATE leases SET state = ? WHERE lease_id = ? AND state = 'active'");
  sqlite::Statement done = db.Cached(
      "UPDATE tasks SET state = 2, result = ?, completions = completions + 1, sample_valid = ? WHERE key = ?");
  sqlite::Statement fenced = db.Cached("UPDATE tasks SET fenced = fenced + 1 WHERE key = ?");
  sqlite::Statement requeue = db.Cached("UPDATE tasks SET state = 0, not_before_ms = ? WHERE key = ?");
  sqlite::Statement failures = db.Cached(
      "SELECT COUNT(*), COUNT(DISTINCT worker_id) FROM leases WHERE task_key = ? AND "
      "(state = 'failed' OR lease_id = ?)");
  sqlite::Statement quarantine = db.Cached(
      "UPDATE tasks SET state = 3, result = ?, completions = completions + 1, "
      "sample_valid = CASE WHEN kind = 1 THEN 0 ELSE -1 END WHERE key = ?");
  sqlite::Statement event = db.Cached("INSERT INTO events (time_ms, job_id, kind, message) VALUES (?,?,?,?)");
};

// The task a completion names, as stored.
struct CompletedTask {
  TaskState state = TaskState::kQueued;
  std::int64_t attempt = 0;
  std::string job_id;
  int kind = 0;
};

// A failed completion on its current lease: the task is quarantined once
// quarantine_after different workers failed it (0 = never), else queued
// again after retry_backoff_ms * 2^(earlier failures), capped at 30 s; an
// event records the worker's reason.
CompletionOutcome Failed(CompletionStatements& s, const Completion& c, const CompletedTask& task, std::int64_t now_ms,
                         std::int64_t retry_backoff_ms, int quarantine_after,
                         const std::function<std::string(int kind)>& quarantine_result, CountDeltas& deltas) {
  s.failures.BindText(1, c.task_key).BindText(2, c.lease_id);
  s.failures.Next();
  const std::int64_t failed_leases = s.failures.ColumnInt(0), failed_workers = s.failures.ColumnInt(1);
  s.failures.Reset();
  CompletionOutcome outcome;
  std::string kind_name = "task_failed";
  if (quarantine_after > 0 && quarantine_result && failed_workers >= quarantine_after) {
    outcome = CompletionOutcome::kQuarantined;
    kind_name = "quarantined";
    s.quarantine.Bind(1, quarantine_result(task.kind)).BindText(2, c.task_key);
    s.quarantine.Run();
    deltas.Moved(task.job_id, TaskState::kLeased, TaskState::kQuarantined);
    if (task.kind == kSampleKind) deltas.Sampled(task.job_id, false);
  } else {
    outcome = CompletionOutcome::kRequeued;
    std::int64_t delay = retry_backoff_ms << std::min<std::int64_t>(std::max<std::int64_t>(failed_leases - 1, 0), 20);
    s.requeue.Bind(1, now_ms + std::min<std::int64_t>(delay, 30000)).BindText(2, c.task_key);
    s.requeue.Run();
    deltas.Moved(task.job_id, TaskState::kLeased, TaskState::kQueued);
  }
  s.event.Bind(1, now_ms).BindText(2, task.job_id).BindText(3, kind_name);
  s.event.BindText(4, "task " + c.task_key.substr(0, 16) + " lease " + c.lease_id + " failed (" +
                          std::to_string(failed_workers) +
                          " worker(s) so far): " + (c.error.empty() ? std::string("no reason given") : c.error));
  s.event.Run();
  return outcome;
}

// An accepted result: the task done, its sample's subtrees recorded.
void Accepted(CompletionStatements& s, const Completion& c, const CompletedTask& task, CountDeltas& deltas) {
  s.done.Bind(1, c.result).Bind(2, std::int64_t{c.sample_valid}).BindText(3, c.task_key);
  s.done.Run();
  deltas.Moved(task.job_id, TaskState::kLeased, TaskState::kDone);
  if (c.sample_valid >= 0) deltas.Sampled(task.job_id, c.sample_valid == 1);
  std::int64_t position = 0;
  for (const SubtreeUse& u : c.subtrees) {
    const std::string children = KeyListText(u.children);
    s.subtree.BindText(1, task.job_id).BindText(2, u.key).BindText(3, u.topology).BindText(4, u.op);
    s.subtree.BindText(5, u.blob_digest).Bind(6, u.bytes).BindText(7, children);
    s.subtree.BindReal(8, u.measured ? u.seconds : 0.0).Bind(9, std::int64_t{u.measured ? 1 : 0});
    s.subtree.BindReal(10, u.seconds);
    s.subtree.Run();
    s.use.BindText(1, c.task_key).Bind(2, position++).BindText(3, task.job_id).BindText(4, c.point_key);
    s.use.BindText(5, u.key);
    s.use.Run();
  }
}

}  // namespace

std::vector<CompletionOutcome> CompleteIn(sqlite::Connection& db, const std::vector<Completion>& completions,
                                          std::int64_t now_ms, std::int64_t retry_backoff_ms, int quarantine_after,
                                          const std::function<std::string(int kind)>& quarantine_result,
                                          CountDeltas& deltas) {
  std::vector<CompletionOutcome> outcomes;
  CompletionStatements s(db);
  for (const Completion& c : completions) {
    s.task.BindText(1, c.task_key);
    if (!s.task.Next()) {
      s.task.Reset();
      outcomes.push_back(CompletionOutcome::kUnknown);
      continue;
    }
    const CompletedTask task{static_cast<TaskState>(s.task.ColumnInt(0)), s.task.ColumnInt(1), s.task.ColumnText(2),
                             static_cast<int>(s.task.ColumnInt(3))};
    s.task.Reset();
    s.lease.BindText(1, c.lease_id).BindText(2, c.task_key).Bind(3, c.attempt);
    const bool active = s.lease.Next() && s.lease.ColumnText(0) == "active";
    s.lease.Reset();
    CompletionOutcome outcome;
    std::string lease_state;
    if (task.state == TaskState::kDone || task.state == TaskState::kQuarantined) {
      outcome = CompletionOutcome::kDuplicate;
      lease_state = "duplicate";
    } else if (!active || task.state != TaskState::kLeased || c.attempt != task.attempt) {
      outcome = CompletionOutcome::kFenced;
      lease_state = "fenced";
      s.fenced.BindText(1, c.task_key);
      s.fenced.Run();
      deltas.Fenced(task.job_id);
    } else if (c.failed) {
      lease_state = "failed";
      outcome = Failed(s, c, task, now_ms, retry_backoff_ms, quarantine_after, quarantine_result, deltas);
    } else {
      outcome = CompletionOutcome::kAccepted;
      lease_state = "completed";
      Accepted(s, c, task, deltas);
    }
    s.set_lease.BindText(1, lease_state).BindText(2, c.lease_id);
    s.set_lease.Run();
    outcomes.push_back(outcome);
  }
  return outcomes;
}

}  // namespace internal

std::vector<CompletionOutcome> JobStore::Complete(const std::vector<Completion>& completions, std::int64_t now_ms,
                                                  std::int64_t retry_backoff_ms, int quarantine_after,
                                                  const std::function<std::string(int kind)>& quarantine_result) {
  if (completions.empty()) return {};
  std::lock_guard lock(mutex_);
  internal::Transaction t(*db_);
  internal::CountDeltas deltas;
  auto outcomes =
      internal::CompleteIn(*db_, completions, now_ms, retry_backoff_ms, quarantine_after, quarantine_result, deltas);
  t.Commit();
  deltas.ApplyTo(counts_);
  return outcomes;
}

}  // namespace fabatlas::storage
