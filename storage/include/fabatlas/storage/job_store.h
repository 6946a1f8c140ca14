// fabatlas/storage/job_store.h — the coordinator's durable state in SQLite
// (WAL mode): jobs, tasks (key, kind, state, attempt, result), leases,
// workers, job outputs and events (docs/protocol.md, docs/operations.md).
//
// Every state change is one SQLite transaction, so a kill -9 at any moment
// leaves a consistent store; the coordinator resumes from it (restart by
// replay, see coordinator/coordinator.h).
//
// Tasks. A task row is keyed by its task key (SHA-256 of kind, canonical
// inputs and code version), so adding a task twice is a no-op and the first
// completion wins: `completions` counts accepted results and is 1 for every
// finished task.
//   queued --GrantLeases--> leased --Complete--> done
//      ^                      |
//      +---- ExpireLeases ----+ (attempt fenced, retry after a backoff;
//                                 the quarantine_after-th expiry -> quarantined)
// Leases. One row per attempt; a lease is active until completed, expired,
// returned or fenced. Lease ids are "<first 16 hex of the key>.<attempt>".
//
// Versions: the schema version is SQLite's user_version. Opening converts a
// store of an older version (0: written before versions existed) in place
// and stamps kJobStoreSchemaVersion; a store of a newer version is refused
// with fabatlas::InputError "<path>: job store written by a newer fabatlas
// (schema version N; ...)" before anything in it changes.
//
// Thread-safe: one connection guarded by a mutex (SQLite serialises writers
// anyway). Errors: an unopenable or unwritable database, a full disk or an
// I/O error throw fabatlas::ResourceError naming the path and SQLite's
// message (they may pass); a file that is not a job store (not SQLite, or
// corrupt) found while opening throws fabatlas::InputError (it will not).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace fabatlas::sqlite {
class Connection;
}  // namespace fabatlas::sqlite

namespace fabatlas::storage {

// Values match fabatlas.v1.JobState.
// The schema version JobStore writes (docs/operations.md, "State").
inline constexpr int kJobStoreSchemaVersion = 1;

enum class JobState { kQueued = 1, kRunning = 2, kSucceeded = 3, kFailed = 4, kCancelled = 5 };
enum class TaskState { kQueued = 0, kLeased = 1, kDone = 2, kQuarantined = 3 };

struct JobRecord {
  std::string id{};
  std::string bundle_digest{};
  std::string design_name{};
  JobState state = JobState::kQueued;
  std::string error{};
  std::int64_t created_ms = 0;
  std::int64_t finished_ms = 0;
};

struct NewTask {
  std::string key{};
  std::string job_id{};
  int kind = 0;           // fabatlas.v1.TaskKind
  std::string payload{};  // serialized fabatlas.v1.TaskPayload
  // Workers this task prefers (lease affinity, worker.proto): GrantLeases
  // hands it to one of them before anyone else. Empty = no preference.
  // Ignored when the task already exists.
  std::vector<std::string> preferred_workers{};
};

struct TaskRecord {
  std::string key{}, job_id{};
  int kind = 0;
  std::string payload{};
  TaskState state = TaskState::kQueued;
  std::int64_t attempt = 0;      // attempts granted so far
  std::int64_t expiries = 0;     // leases that expired
  std::int64_t completions = 0;  // accepted results (0 or 1)
  std::string result{};          // serialized fabatlas.v1.TaskResult
};

struct LeaseGrant {
  std::string lease_id{}, task_key{}, job_id{}, bundle_digest{};
  std::int64_t attempt = 0;
  int kind = 0;
  std::string payload{};
  std::int64_t deadline_ms = 0;
};

// One subtree root of a sample (fabatlas.v1.SubtreeRecord).
struct SubtreeUse {
  std::string key{};       // cache key: hex SHA-256 of (τ, ρ, voxel size)
  std::string topology{};  // hex SHA-256 of τ
  std::string op{};
  double seconds = 0;                   // root compute time on the worker (for a cache hit:
                                        // the worker's last measurement of the key)
  bool measured = true;                 // false for a cache hit
  std::int64_t bytes = 0;               // memory of the level set
  std::vector<std::string> children{};  // child keys, in tree order
  std::string blob_digest{};            // serialized Solid in the blob store, or ""
};

struct Completion {
  std::string lease_id{}, task_key{};
  std::int64_t attempt = 0;
  std::string result{};   // serialized TaskResult; ignored when failed
  bool failed = false;    // the worker could not run the task: requeue
  int sample_valid = -1;  // sample tasks: 1 valid, 0 invalid; -1 otherwise
  // Sample tasks: the point key ("k0,k1,..." as in the task key) and the
  // sample's subtrees, post-order (root last); stored only when the result
  // is accepted, in the same transaction.
  std::string point_key{};
  std::vector<SubtreeUse> subtrees{};
  std::string error{};  // when failed: the worker's one-line reason (events)
};

enum class CompletionOutcome {
  kAccepted,     // stored; the first completion of the key
  kDuplicate,    // the key was already finished: acknowledged, ignored
  kFenced,       // the lease is no longer current (expired, returned): ignored
  kUnknown,      // no such task
  kRequeued,     // failed: the task goes back to the queue
  kQuarantined,  // failed on quarantine_after different workers: finished
                 // with the quarantine result, like an expiry quarantine
};

// One worker's Sync (worker.proto) against the store: what it reports and
// asks for (JobStore::SyncWorker).
struct WorkerSync {
  std::string worker_id{};
  std::vector<Completion> completions{};  // results it reports
  std::vector<std::string> in_flight{};   // leases it still holds (running or queued)
  std::int64_t now_ms = 0;
  std::int64_t lease_ms = 0;  // leases granted or topped up run until now_ms + lease_ms
  int want = 0;               // leases to grant at most (0: none)
  int steal = -1;             // of them, tasks preferring other workers at most (< 0: want)
  // As for Complete.
  std::int64_t retry_backoff_ms = 0;
  int quarantine_after = 0;
  std::function<std::string(int kind)> quarantine_result{};
};

struct WorkerSyncOutcome {
  std::vector<CompletionOutcome> outcomes{};  // one per completion, in order
  int returned = 0;                           // its active leases it no longer knows, queued again
  std::vector<std::string> revoked{};         // in_flight ids that are not active leases of the worker
  std::vector<LeaseGrant> grants{};           // new leases
};

struct ExpiredLease {
  std::string lease_id{}, task_key{}, job_id{}, worker_id{};
  std::int64_t attempt = 0;   // the lease's attempt number (fencing)
  std::int64_t expiries = 0;  // the task's expiries, this one included
  bool quarantined = false;
};

struct TaskCounts {
  std::int64_t total = 0, queued = 0, leased = 0, done = 0, quarantined = 0;
  std::int64_t samples_done = 0, samples_valid = 0;
  std::int64_t lease_expiries = 0, fenced_results = 0;
};

// A subtree of a job, over all its accepted sample results (the geometry
// cache's dependency graph, Fab Forms Sec. 6).
struct SubtreeRow {
  std::string key{}, topology{}, op{};
  std::string blob_digest{};  // first non-empty digest reported, or ""
  std::int64_t bytes = 0;
  std::vector<std::string> children{};
  double seconds_sum = 0;          // over measured (not cached) evaluations
  std::int64_t seconds_count = 0;  // how many measured evaluations
  double last_seconds = 0;         // latest reported seconds (measured or carried)
  std::int64_t uses = 0;           // accepted samples containing it
  // Mean measured seconds, or last_seconds when none was measured.
  double seconds() const { return seconds_count ? seconds_sum / seconds_count : last_seconds; }
};

// The subtrees of one accepted sample, post-order (root last).
struct SampleSubtrees {
  std::string task_key{};
  std::string point_key{};  // "k0,k1,..." (sampling::PointKey in decimal)
  std::vector<std::string> subtree_keys{};
};

struct Event {
  std::int64_t time_ms = 0;
  std::string job_id{}, kind{}, message{};
};

// Durability. The store runs in WAL mode. With synchronous=NORMAL (the
// default) a commit is written to the WAL but not fsynced: it survives a
// kill -9 or crash of the coordinator at any moment, but a power loss or OS
// crash may roll back the transactions committed since the last WAL sync
// (at the latest, the last checkpoint). The store stays consistent either
// way (SQLite rolls back whole transactions), and what a rollback undoes is
// only recorded progress: the tasks it un-finishes are leased again and
// recomputed with the same result (tasks are deterministic), so a job's
// outputs are never lost or wrong, only some work is redone. To have every
// acknowledged result survive a power loss too, set fsync_every_commit
// (synchronous=FULL: one WAL fsync per commit).
struct JobStoreOptions {
  bool fsync_every_commit = false;
  // No checkpoints inside commits (SQLite's automatic checkpoint every 1000
  // WAL pages fsyncs the database in whichever call commits): the owner
  // calls Checkpoint() periodically from a thread of its own instead.
  bool background_checkpoints = false;
};

class JobStore {
 public:
  // Opens or creates the database (WAL, synchronous=NORMAL or FULL, see
  // JobStoreOptions).
  explicit JobStore(const std::filesystem::path& path, JobStoreOptions options = {});
  ~JobStore();
  JobStore(const JobStore&) = delete;
  JobStore& operator=(const JobStore&) = delete;

  const std::filesystem::path& path() const { return path_; }

  // --- jobs ---
  // Inserts the job; false (and nothing changed) when the id exists.
  bool CreateJob(const JobRecord& job);
  std::optional<JobRecord> FindJob(const std::string& id);
  std::vector<JobRecord> Jobs();
  void SetJobState(const std::string& id, JobState state, const std::string& error, std::int64_t finished_ms);
  void PutJobOutput(const std::string& job_id, const std::string& name, const std::string& digest);
  std::map<std::string, std::string> JobOutputs(const std::string& job_id);

  // --- tasks ---
  // Inserts the tasks that do not exist yet (one transaction). Returns the
  // stored result of every given key that is already done or quarantined.
  std::map<std::string, std::string> AddTasks(const std::vector<NewTask>& tasks);
  std::optional<TaskRecord> FindTask(const std::string& key);
  std::vector<TaskRecord> Tasks(const std::string& job_id);

  // --- scheduling ---
  // Leases up to `max` queued tasks of running jobs whose backoff has passed
  // to `worker_id` until now_ms + lease_ms, in the order of lease affinity
  // (worker.proto): tasks preferring this worker (fewest preferred workers
  // first, then oldest), then tasks preferring nobody (oldest first), then
  // tasks preferring other workers (newest first; at most `steal` of them,
  // all `max` when negative). A granted task's preference is dropped.
  std::vector<LeaseGrant> GrantLeases(const std::string& worker_id, int max, std::int64_t now_ms, std::int64_t lease_ms,
                                      int steal = -1);
  // Drops every preference for the worker (it left or went silent); tasks
  // left without a preferred worker prefer nobody. Returns how many tasks
  // lost it.
  int ForgetAffinity(const std::string& worker_id);
  // Drops every preference (coordinator start: worker liveness is unknown).
  void ClearAffinity();
  // Applies the results (one transaction); outcomes in input order.
  // A failed task is queued again after retry_backoff_ms * 2^(earlier
  // failures) (capped at 30 s) and an event records the worker's reason;
  // once quarantine_after different workers have failed it (0 = never), it
  // is finished with quarantine_result(kind) instead, so a task no worker
  // can run ends the job's wait rather than cycling forever, while one
  // misconfigured worker failing everything quarantines nothing.
  std::vector<CompletionOutcome> Complete(const std::vector<Completion>& completions, std::int64_t now_ms,
                                          std::int64_t retry_backoff_ms, int quarantine_after = 0,
                                          const std::function<std::string(int kind)>& quarantine_result = {});
  // A worker's Sync in one transaction (one commit at most, none when
  // nothing changes): Complete(completions), then ReturnUnknownLeases(
  // in_flight + the completions' leases), ExtendLeases(in_flight, now_ms +
  // lease_ms, slack lease_ms / 2), then GrantLeases(want, steal). The same outcome
  // as those calls in that order; a kill -9 keeps all of it or none (a
  // worker whose Sync got no answer reports again: its results are accepted
  // or acknowledged as duplicates, and leases it never heard of are returned
  // by its next Sync or expire).
  WorkerSyncOutcome SyncWorker(const WorkerSync& sync);
  // Moves the deadline of the worker's listed active leases to deadline_ms,
  // leaving (not writing) those already due at deadline_ms - slack_ms or
  // later. Returns the listed ids that are not active leases of this worker.
  std::vector<std::string> ExtendLeases(const std::string& worker_id, const std::vector<std::string>& lease_ids,
                                        std::int64_t deadline_ms, std::int64_t slack_ms = 0);
  // Active leases of the worker that are not in `known` (lost in transit or
  // forgotten by a restarted worker) go back to the queue at once, without
  // counting as an expiry. Returns how many.
  int ReturnUnknownLeases(const std::string& worker_id, const std::vector<std::string>& known);
  // Expires every active lease whose deadline is before now_ms: the task is
  // queued again, eligible after backoff_ms * 2^(expiries-1) (capped at 30 s),
  // or, on its quarantine_after-th expiry, finished with
  // quarantine_result(kind) and marked quarantined.
  std::vector<ExpiredLease> ExpireLeases(std::int64_t now_ms, std::int64_t backoff_ms, int quarantine_after,
                                         const std::function<std::string(int kind)>& quarantine_result);
  // Gives every active lease until now_ms + grace_ms (used at start-up, so
  // workers that kept running while the coordinator was down can report).
  void ExtendAllLeases(std::int64_t deadline_ms);
  // Counts for one job, or for all jobs when job_id is empty. A job's counts
  // are read from the tasks once (a scan of its tasks) and then kept in
  // memory, moved by every change this store commits, so a status poll costs
  // O(1) however many tasks the job has; all jobs' counts are a scan.
  TaskCounts CountTasks(const std::string& job_id);
  std::int64_t ActiveLeases();

  // --- subtrees (geometry cache records, tasks.proto SubtreeRecord) ---
  // Every subtree of the job's accepted sample results, by key. Recorded
  // when a sample result is accepted (first accepted result of a task key
  // wins; duplicates and fenced results add nothing), so a job re-run after
  // a restart never counts a sample twice.
  std::vector<SubtreeRow> Subtrees(const std::string& job_id);
  // Sample -> subtree keys for the job's accepted sample results, in task
  // order.
  std::vector<SampleSubtrees> SampleSubtreeKeys(const std::string& job_id);

  // --- blob references (docs/protocol.md "Blob lifecycle") ---
  // Records that the job uses the blob until it ends (e.g. its cache plan's
  // input and report, its swept-volume surfaces). Idempotent.
  void AddJobBlob(const std::string& job_id, const std::string& digest);
  // Every blob the store still needs, sorted, unique: every job's bundle and
  // published outputs, and for jobs not yet ended (queued or running) their
  // subtree geometry (SubtreeRow.blob_digest) and AddJobBlob blobs. The
  // geometry of a job that ended is no longer needed: its artifact holds
  // what the cache plan kept (a failed or cancelled job resubmitted
  // evaluates what it misses again).
  std::vector<std::string> ReferencedBlobs();
  // granted_ms of the oldest active lease, or -1 when none is active.
  std::int64_t OldestActiveLeaseMs();

  // --- workers ---
  // Records that the worker was seen (at most one write per worker and second:
  // last_seen_ms is precise to 1 s).
  void TouchWorker(const std::string& worker_id, int slots, std::int64_t now_ms);
  // Workers seen since since_ms.
  std::int64_t CountWorkers(std::int64_t since_ms);

  // --- events ---
  void AddEvent(const Event& event);
  std::vector<Event> Events(const std::string& job_id);

  // Invariants, for tests and `fabatlas-coordinator --check`: every finished
  // task completed exactly once, no active lease on a task that is not
  // leased, every leased task has exactly one active lease, and every job's
  // counts kept in memory (CountTasks) equal a scan of its tasks. Returns one
  // line per violation (empty = consistent).
  std::vector<std::string> CheckConsistency();

  // Makes every transaction committed so far survive a power loss (one
  // fsync of the WAL), whatever fsync_every_commit says. For the few
  // commits a client or a deletion depends on: a submitted job (the client
  // was told its id) and the references blob collection reads (a blob swept
  // because a job ended must never be needed again by a store rolled back to
  // before that end). Throws ResourceError when the sync fails.
  void Sync();

  // Copies committed WAL pages into the database file (a PASSIVE checkpoint
  // on a second connection, so commits go on meanwhile). Returns the pages
  // checkpointed. For background_checkpoints.
  int Checkpoint();

 private:
  std::filesystem::path path_;
  JobStoreOptions options_;
  std::unique_ptr<sqlite::Connection> db_;
  std::mutex mutex_;
  std::map<std::string, std::pair<int, std::int64_t>> touched_;  // worker -> (slots, last write ms)
  std::int64_t preferring_tasks_ = 0;                            // tasks with tasks.affine = 1 (lease affinity)
  // CountTasks of each job asked for so far, moved by every committed change
  // (task_counts.h CountDeltas); under mutex_.
  std::map<std::string, TaskCounts> counts_;
  std::int64_t synced_changes_ = -1;  // sqlite3_total_changes64 at the last Sync; under mutex_
  std::mutex checkpoint_mutex_;
  std::unique_ptr<sqlite::Connection> checkpoint_db_;  // Checkpoint()'s own
};

}  // namespace fabatlas::storage
