// The job store: opening, durability (Sync, Checkpoint), jobs, tasks,
// subtrees, blob references, workers, events and the consistency check (see
// job_store.h). Leases are leases.cc, completions completions.cc, a worker's
// Sync worker_sync.cc, task counts task_counts.cc, the tables schema.cc.
#include "fabatlas/storage/job_store.h"

#include <sqlite3.h>

#include "fabatlas/error.h"
#include "fabatlas/key_list_text.h"
#include "fabatlas/sqlite/connection.h"
#include "schema.h"
#include "task_counts.h"
#include "transaction.h"

namespace fabatlas::storage {

using internal::CountDeltas;
using internal::CountsText;
using internal::ScanCounts;
using internal::Transaction;

namespace {

// A connection to the store at `path`; its errors are ResourceErrors naming
// the path.
std::unique_ptr<sqlite::Connection> OpenConnection(const std::filesystem::path& path, int flags,
                                                   const std::string& opening) {
  const std::string name = path.string();
  return std::make_unique<sqlite::Connection>(
      name, flags, [name](const std::string& message) { throw ResourceError(name + ": " + message); }, opening);
}

// A job row: the columns of kJobColumns, in their order.
constexpr const char* kJobColumns =
    "SELECT id, bundle_digest, design_name, state, error, created_ms, finished_ms FROM jobs ";
JobRecord ReadJob(const sqlite::Statement& s) {
  return {s.ColumnText(0), s.ColumnText(1), s.ColumnText(2), static_cast<JobState>(s.ColumnInt(3)),
          s.ColumnText(4), s.ColumnInt(5),  s.ColumnInt(6)};
}

// A task row: the columns of kTaskColumns, in their order.
constexpr const char* kTaskColumns =
    "SELECT key, job_id, kind, payload, state, attempt, expiries, completions, result FROM tasks ";
TaskRecord ReadTask(const sqlite::Statement& s) {
  return {s.ColumnText(0),
          s.ColumnText(1),
          static_cast<int>(s.ColumnInt(2)),
          s.ColumnText(3),
          static_cast<TaskState>(s.ColumnInt(4)),
          s.ColumnInt(5),
          s.ColumnInt(6),
          s.ColumnInt(7),
          s.ColumnText(8)};
}

}  // namespace

JobStore::JobStore(const std::filesystem::path& path, JobStoreOptions options) : path_(path), options_(options) {
  std::error_code ec;
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path(), ec);
  db_ = OpenConnection(path, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX,
                       "cannot open the job store");
  try {
    sqlite3_busy_timeout(db_->get(), 10000);
    // Refuse a store a newer coordinator wrote before touching it.
    internal::CheckSchemaVersion(*db_, path.string());
    db_->Exec("PRAGMA journal_mode=WAL");
    db_->Exec(options_.fsync_every_commit ? "PRAGMA synchronous=FULL" : "PRAGMA synchronous=NORMAL");
    if (options_.background_checkpoints) sqlite3_wal_autocheckpoint(db_->get(), 0);
    // When a commit starts the WAL over (after a checkpoint RESTART,
    // Checkpoint()), a file grown past 16 MiB while checkpoints could not keep
    // up is cut back to 16 MiB: the WAL reuses its pages without keeping its
    // high-water mark on disk. 16 rather than the restart's 8 MiB: a
    // checkpoint comes once a second, so the WAL passes 8 MiB by up to a
    // second of commits, and cutting those pages off at every restart would
    // make the next pass extend the file again.
    db_->Exec("PRAGMA journal_size_limit = 16777216");
    internal::MigrateSchema(*db_);
    preferring_tasks_ = db_->ExecInt("SELECT COUNT(*) FROM tasks WHERE affine = 1");
  } catch (const ResourceError& e) {
    // Not a database, or a corrupt one: no restart makes it one (bad input,
    // exit 2 in the coordinator); an I/O error or a full disk may pass.
    const int code = sqlite3_errcode(db_->get()) & 0xff;
    if (code == SQLITE_NOTADB || code == SQLITE_CORRUPT) throw InputError(e.what());
    throw;
  }
}

JobStore::~JobStore() = default;

void JobStore::Sync() {
  std::lock_guard lock(mutex_);
  // Nothing committed since the last Sync: nothing to make durable (an idle
  // coordinator's periodic blob collection costs no fsync).
  const std::int64_t changes = sqlite3_total_changes64(db_->get());
  if (changes == synced_changes_) return;
  // The WAL's file (SQLITE_FCNTL_JOURNAL_POINTER): with synchronous=NORMAL
  // SQLite syncs it only at checkpoints, and a commit is durable once its
  // frames are (SQLite, "Write-Ahead Logging", docs/references.md).
  sqlite3_file* wal = nullptr;
  if (sqlite3_file_control(db_->get(), "main", SQLITE_FCNTL_JOURNAL_POINTER, &wal) != SQLITE_OK)
    db_->Fail("find the write-ahead log");
  if (!wal || !wal->pMethods) {  // no WAL open: every commit is in the database file, synced
    synced_changes_ = changes;
    return;
  }
  if (wal->pMethods->xSync(wal, SQLITE_SYNC_NORMAL) != SQLITE_OK)
    throw ResourceError(path_.string() + "-wal: cannot sync the write-ahead log");
  synced_changes_ = changes;
}

int JobStore::Checkpoint() {
  std::lock_guard lock(checkpoint_mutex_);
  if (!checkpoint_db_) {
    checkpoint_db_ = OpenConnection(path_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_FULLMUTEX,
                                    "cannot open the job store for checkpoints");
    sqlite3_busy_timeout(checkpoint_db_->get(), 1000);
    checkpoint_db_->Exec(options_.fsync_every_commit ? "PRAGMA synchronous=FULL" : "PRAGMA synchronous=NORMAL");
  }
  int log = 0, done = 0;
  int rc = sqlite3_wal_checkpoint_v2(checkpoint_db_->get(), nullptr, SQLITE_CHECKPOINT_PASSIVE, &log, &done);
  if (rc != SQLITE_OK && rc != SQLITE_BUSY) checkpoint_db_->Fail("checkpoint");
  // Under a steady stream of commits a passive checkpoint never catches up
  // with the last frame, so the WAL never restarts and grows with the job.
  // Past kWalRestartFrames (8 MiB of 4 KiB
  // pages), a RESTART checkpoint waits (busy timeout) for the writer, copies
  // the rest, and the next commit writes from the WAL's start again: the WAL
  // stays bounded whatever the job's size. RESTART rather than TRUNCATE: the
  // file keeps its pages, so commits overwrite pages the kernel has cached
  // instead of extending an emptied file (a new page cache page and a block
  // reservation per frame; measured in docs/benchmarks-history.md, "Scale").
  constexpr int kWalRestartFrames = 2048;
  if (log > kWalRestartFrames) {
    rc = sqlite3_wal_checkpoint_v2(checkpoint_db_->get(), nullptr, SQLITE_CHECKPOINT_RESTART, &log, &done);
    if (rc != SQLITE_OK && rc != SQLITE_BUSY) checkpoint_db_->Fail("checkpoint");
  }
  return done;
}

bool JobStore::CreateJob(const JobRecord& job) {
  std::lock_guard lock(mutex_);
  auto s = db_->Cached(
      "INSERT OR IGNORE INTO jobs (id, bundle_digest, design_name, state, error, created_ms, "
      "finished_ms) VALUES (?,?,?,?,?,?,?)");
  s.BindText(1, job.id).BindText(2, job.bundle_digest).BindText(3, job.design_name);
  s.Bind(4, static_cast<std::int64_t>(job.state)).BindText(5, job.error);
  s.Bind(6, job.created_ms).Bind(7, job.finished_ms);
  s.Run();
  return sqlite3_changes(db_->get()) == 1;
}

std::optional<JobRecord> JobStore::FindJob(const std::string& id) {
  std::lock_guard lock(mutex_);
  auto s = db_->Cached(std::string(kJobColumns) + "WHERE id = ?");
  s.BindText(1, id);
  if (!s.Next()) return std::nullopt;
  return ReadJob(s);
}

std::vector<JobRecord> JobStore::Jobs() {
  std::lock_guard lock(mutex_);
  auto s = db_->Cached(std::string(kJobColumns) + "ORDER BY created_ms, id");
  return s.Rows(ReadJob);
}

void JobStore::SetJobState(const std::string& id, JobState state, const std::string& error, std::int64_t finished_ms) {
  std::lock_guard lock(mutex_);
  auto s = db_->Cached("UPDATE jobs SET state = ?, error = ?, finished_ms = ? WHERE id = ?");
  s.Bind(1, static_cast<std::int64_t>(state)).BindText(2, error).Bind(3, finished_ms).BindText(4, id);
  s.Run();
}

void JobStore::PutJobOutput(const std::string& job_id, const std::string& name, const std::string& digest) {
  std::lock_guard lock(mutex_);
  auto s = db_->Cached("INSERT OR REPLACE INTO job_outputs (job_id, name, digest) VALUES (?,?,?)");
  s.BindText(1, job_id).BindText(2, name).BindText(3, digest);
  s.Run();
}

std::map<std::string, std::string> JobStore::JobOutputs(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  auto s = db_->Cached("SELECT name, digest FROM job_outputs WHERE job_id = ? ORDER BY name");
  s.BindText(1, job_id);
  std::map<std::string, std::string> out;
  while (s.Next()) out[s.ColumnText(0)] = s.ColumnText(1);
  return out;
}

std::map<std::string, std::string> JobStore::AddTasks(const std::vector<NewTask>& tasks) {
  std::lock_guard lock(mutex_);
  Transaction t(*db_);
  auto insert = db_->Cached("INSERT OR IGNORE INTO tasks (key, job_id, kind, payload, affine) VALUES (?,?,?,?,?)");
  auto find = db_->Cached("SELECT result FROM tasks WHERE key = ? AND state IN (2, 3)");
  auto prefer = db_->Cached("INSERT OR IGNORE INTO task_affinity (worker_id, rank, task_seq) VALUES (?,?,?)");
  std::map<std::string, std::string> finished;
  CountDeltas deltas;
  std::int64_t preferring = 0;
  for (const NewTask& task : tasks) {
    insert.BindText(1, task.key).BindText(2, task.job_id).Bind(3, std::int64_t{task.kind});
    insert.Bind(4, task.payload).Bind(5, std::int64_t{task.preferred_workers.empty() ? 0 : 1});
    insert.Run();
    insert.Reset();
    const bool inserted = sqlite3_changes(db_->get()) == 1;
    if (inserted) deltas.Added(task.job_id);
    if (!task.preferred_workers.empty() && inserted) {
      // rank: how many workers share the preference (fewer = more this worker's own)
      std::int64_t seq = sqlite3_last_insert_rowid(db_->get());
      ++preferring;
      for (const auto& worker : task.preferred_workers) {
        prefer.BindText(1, worker).Bind(2, static_cast<std::int64_t>(task.preferred_workers.size())).Bind(3, seq);
        prefer.Run();
        prefer.Reset();
      }
    }
    find.BindText(1, task.key);
    if (find.Next()) finished[task.key] = find.ColumnText(0);
    find.Reset();
  }
  t.Commit();
  preferring_tasks_ += preferring;
  deltas.ApplyTo(counts_);
  return finished;
}

std::optional<TaskRecord> JobStore::FindTask(const std::string& key) {
  std::lock_guard lock(mutex_);
  auto s = db_->Cached(std::string(kTaskColumns) + "WHERE key = ?");
  s.BindText(1, key);
  if (!s.Next()) return std::nullopt;
  return ReadTask(s);
}

std::vector<TaskRecord> JobStore::Tasks(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  auto s = db_->Cached(std::string(kTaskColumns) + "WHERE job_id = ? ORDER BY seq");
  s.BindText(1, job_id);
  return s.Rows(ReadTask);
}

std::vector<SubtreeRow> JobStore::Subtrees(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  auto s = db_->Cached(
      "SELECT key, topology, op, digest, bytes, children, seconds_sum, seconds_count, last_seconds, uses "
      "FROM subtrees WHERE job_id = ? ORDER BY key");
  s.BindText(1, job_id);
  return s.Rows([](const sqlite::Statement& row) {
    SubtreeRow r;
    r.key = row.ColumnText(0);
    r.topology = row.ColumnText(1);
    r.op = row.ColumnText(2);
    r.blob_digest = row.ColumnText(3);
    r.bytes = row.ColumnInt(4);
    r.children = ParseKeyListText(row.ColumnText(5));
    r.seconds_sum = row.ColumnReal(6);
    r.seconds_count = row.ColumnInt(7);
    r.last_seconds = row.ColumnReal(8);
    r.uses = row.ColumnInt(9);
    return r;
  });
}

std::vector<SampleSubtrees> JobStore::SampleSubtreeKeys(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  auto s = db_->Cached(
      "SELECT u.task_key, u.point_key, u.subtree_key FROM sample_subtrees u JOIN tasks t ON t.key = "
      "u.task_key WHERE u.job_id = ? ORDER BY t.seq, u.position");
  s.BindText(1, job_id);
  std::vector<SampleSubtrees> out;
  while (s.Next()) {
    if (out.empty() || out.back().task_key != s.ColumnText(0)) out.push_back({s.ColumnText(0), s.ColumnText(1), {}});
    out.back().subtree_keys.push_back(s.ColumnText(2));
  }
  return out;
}

void JobStore::AddJobBlob(const std::string& job_id, const std::string& digest) {
  std::lock_guard lock(mutex_);
  auto s = db_->Cached("INSERT OR IGNORE INTO job_blobs (job_id, digest) VALUES (?,?)");
  s.BindText(1, job_id).BindText(2, digest);
  s.Run();
}

std::vector<std::string> JobStore::ReferencedBlobs() {
  std::lock_guard lock(mutex_);
  // Jobs not ended: queued (1) or running (2).
  auto s = db_->Cached(
      "SELECT bundle_digest FROM jobs UNION SELECT digest FROM job_outputs "
      "UNION SELECT s.digest FROM subtrees s JOIN jobs j ON j.id = s.job_id WHERE j.state IN (1, 2) "
      "AND s.digest != '' "
      "UNION SELECT b.digest FROM job_blobs b JOIN jobs j ON j.id = b.job_id WHERE j.state IN (1, 2) "
      "ORDER BY 1");
  return s.Rows([](const sqlite::Statement& row) { return row.ColumnText(0); });
}

void JobStore::TouchWorker(const std::string& worker_id, int slots, std::int64_t now_ms) {
  std::lock_guard lock(mutex_);
  // At most one write per worker and second (last_seen_ms is precise to 1 s).
  auto& touched = touched_[worker_id];
  if (touched.second != 0 && touched.second <= now_ms && now_ms - touched.second < 1000) return;
  touched = {slots, now_ms};
  auto s = db_->Cached(
      "INSERT INTO workers (id, slots, first_seen_ms, last_seen_ms) VALUES (?,?,?,?) "
      "ON CONFLICT(id) DO UPDATE SET slots = excluded.slots, last_seen_ms = excluded.last_seen_ms");
  s.BindText(1, worker_id).Bind(2, std::int64_t{slots}).Bind(3, now_ms).Bind(4, now_ms);
  s.Run();
}

std::int64_t JobStore::CountWorkers(std::int64_t since_ms) {
  std::lock_guard lock(mutex_);
  auto s = db_->Cached("SELECT COUNT(*) FROM workers WHERE last_seen_ms >= ?");
  s.Bind(1, since_ms);
  s.Next();
  return s.ColumnInt(0);
}

void JobStore::AddEvent(const Event& event) {
  std::lock_guard lock(mutex_);
  auto s = db_->Cached("INSERT INTO events (time_ms, job_id, kind, message) VALUES (?,?,?,?)");
  s.Bind(1, event.time_ms).BindText(2, event.job_id).BindText(3, event.kind);
  s.BindText(4, event.message);
  s.Run();
}

std::vector<Event> JobStore::Events(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  auto s = db_->Cached("SELECT time_ms, job_id, kind, message FROM events WHERE job_id = ? ORDER BY id");
  s.BindText(1, job_id);
  return s.Rows([](const sqlite::Statement& row) {
    return Event{row.ColumnInt(0), row.ColumnText(1), row.ColumnText(2), row.ColumnText(3)};
  });
}

std::vector<std::string> JobStore::CheckConsistency() {
  std::lock_guard lock(mutex_);
  std::vector<std::string> problems;
  {
    auto s = db_->Cached("SELECT key, completions FROM tasks WHERE state IN (2, 3) AND completions != 1");
    while (s.Next())
      problems.push_back("task " + s.ColumnText(0) + " completed " + std::to_string(s.ColumnInt(1)) + " times");
  }
  {
    auto s = db_->Cached(
        "SELECT l.lease_id FROM leases l JOIN tasks t ON t.key = l.task_key WHERE "
        "l.state = 'active' AND (t.state != 1 OR t.attempt != l.attempt)");
    while (s.Next()) problems.push_back("orphaned active lease " + s.ColumnText(0));
  }
  {
    auto s = db_->Cached(
        "SELECT t.key FROM tasks t WHERE t.state = 1 AND (SELECT COUNT(*) FROM leases l WHERE "
        "l.task_key = t.key AND l.state = 'active') != 1");
    while (s.Next()) problems.push_back("leased task " + s.ColumnText(0) + " without one active lease");
  }
  {
    auto s = db_->Cached("SELECT key FROM tasks WHERE state IN (0, 1) AND completions != 0");
    while (s.Next()) problems.push_back("unfinished task " + s.ColumnText(0) + " has a result");
  }
  for (const auto& [job_id, kept] : counts_) {
    const TaskCounts scanned = ScanCounts(*db_, job_id);
    if (CountsText(kept) != CountsText(scanned))
      problems.push_back("job " + job_id + " counts " + CountsText(kept) + " in memory but " + CountsText(scanned) +
                         " in its tasks");
  }
  return problems;
}

}  // namespace fabatlas::storage
