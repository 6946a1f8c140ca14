// A job's task counts: the scan, the per-transaction deltas and
// JobStore::CountTasks (see task_counts.h).
#include "task_counts.h"

#include <mutex>

namespace fabatlas::storage {
namespace internal {

namespace {

std::int64_t& CountOf(TaskCounts& c, TaskState state) {
  switch (state) {
    case TaskState::kQueued:
      return c.queued;
    case TaskState::kLeased:
      return c.leased;
    case TaskState::kDone:
      return c.done;
    case TaskState::kQuarantined:
      break;
  }
  return c.quarantined;
}

}  // namespace

TaskCounts ScanCounts(sqlite::Connection& db, const std::string& job_id) {
  const std::string where = job_id.empty() ? "" : " WHERE job_id = ?";
  auto s = db.Cached(
      "SELECT state, COUNT(*), SUM(sample_valid = 1), SUM(sample_valid >= 0), "
      "SUM(expiries), SUM(fenced) FROM tasks" +
      where + " GROUP BY state");
  if (!job_id.empty()) s.BindText(1, job_id);
  TaskCounts c;
  while (s.Next()) {
    std::int64_t n = s.ColumnInt(1);
    c.total += n;
    CountOf(c, static_cast<TaskState>(s.ColumnInt(0))) += n;
    if (s.ColumnInt(0) >= 2) {
      c.samples_valid += s.ColumnInt(2);
      c.samples_done += s.ColumnInt(3);
    }
    c.lease_expiries += s.ColumnInt(4);
    c.fenced_results += s.ColumnInt(5);
  }
  return c;
}

std::string CountsText(const TaskCounts& c) {
  return std::to_string(c.total) + " tasks (" + std::to_string(c.queued) + " queued, " + std::to_string(c.leased) +
         " leased, " + std::to_string(c.done) + " done, " + std::to_string(c.quarantined) + " quarantined), " +
         std::to_string(c.samples_done) + " samples (" + std::to_string(c.samples_valid) + " valid), " +
         std::to_string(c.lease_expiries) + " expiries, " + std::to_string(c.fenced_results) + " fenced";
}

void CountDeltas::Added(const std::string& job_id) {
  ++deltas_[job_id].total;
  ++deltas_[job_id].queued;
}

void CountDeltas::Moved(const std::string& job_id, TaskState from, TaskState to) {
  TaskCounts& d = deltas_[job_id];
  --CountOf(d, from);
  ++CountOf(d, to);
}

void CountDeltas::Sampled(const std::string& job_id, bool valid) {
  ++deltas_[job_id].samples_done;
  if (valid) ++deltas_[job_id].samples_valid;
}

void CountDeltas::ApplyTo(std::map<std::string, TaskCounts>& counts) const {
  for (const auto& [job_id, d] : deltas_) {
    auto it = counts.find(job_id);
    if (it == counts.end()) continue;  // not asked for yet: its first CountTasks scans
    TaskCounts& c = it->second;
    c.total += d.total;
    c.queued += d.queued;
    c.leased += d.leased;
    c.done += d.done;
    c.quarantined += d.quarantined;
    c.samples_done += d.samples_done;
    c.samples_valid += d.samples_valid;
    c.lease_expiries += d.lease_expiries;
    c.fenced_results += d.fenced_results;
  }
}

}  // namespace internal

TaskCounts JobStore::CountTasks(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  if (job_id.empty()) return internal::ScanCounts(*db_, job_id);
  auto it = counts_.find(job_id);
  if (it == counts_.end()) it = counts_.emplace(job_id, internal::ScanCounts(*db_, job_id)).first;
  return it->second;
}

}  // namespace fabatlas::storage
