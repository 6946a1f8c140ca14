// A job's task counts (JobStore::CountTasks): a scan of its tasks, and the
// changes one transaction makes to them (internal to storage/).
#pragma once

#include <map>
#include <string>

#include "fabatlas/sqlite/connection.h"
#include "fabatlas/storage/job_store.h"

namespace fabatlas::storage::internal {

inline constexpr int kSampleKind = 1;  // fabatlas.v1.TASK_KIND_SAMPLE

// A job's task counts by a scan of its tasks (of all tasks for "").
TaskCounts ScanCounts(sqlite::Connection& db, const std::string& job_id);

// One line naming every count (CheckConsistency's comparison and message).
std::string CountsText(const TaskCounts& c);

// The changes one transaction makes to its jobs' task counts, applied to the
// counts kept in memory (JobStore::counts_) once it commits: a transaction
// rolled back moves nothing.
class CountDeltas {
 public:
  // A new task (queued).
  void Added(const std::string& job_id);
  void Moved(const std::string& job_id, TaskState from, TaskState to);
  // A sample task finished (done or quarantined), valid or not.
  void Sampled(const std::string& job_id, bool valid);
  void Expired(const std::string& job_id) { ++deltas_[job_id].lease_expiries; }
  void Fenced(const std::string& job_id) { ++deltas_[job_id].fenced_results; }
  // Adds the deltas to the jobs of `counts` (jobs not asked for yet are
  // left out: their first CountTasks scans).
  void ApplyTo(std::map<std::string, TaskCounts>& counts) const;

 private:
  std::map<std::string, TaskCounts> deltas_;
};

}  // namespace fabatlas::storage::internal
