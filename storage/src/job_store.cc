// SQLite job store (see job_store.h).
#include "fabatlas/storage/job_store.h"

#include <sqlite3.h>

#include <algorithm>
#include <cstdio>
#include <set>

#include "fabatlas/error.h"
#include "fabatlas/key_list_text.h"
#include "fabatlas/sqlite/statement.h"

namespace fabatlas::storage {

namespace {

constexpr const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS jobs (
  id TEXT PRIMARY KEY, bundle_digest TEXT NOT NULL, design_name TEXT NOT NULL,
  state INTEGER NOT NULL, error TEXT NOT NULL DEFAULT '',
  created_ms INTEGER NOT NULL, finished_ms INTEGER NOT NULL DEFAULT 0);
CREATE TABLE IF NOT EXISTS job_outputs (
  job_id TEXT NOT NULL, name TEXT NOT NULL, digest TEXT NOT NULL,
  PRIMARY KEY (job_id, name));
CREATE TABLE IF NOT EXISTS tasks (
  seq INTEGER PRIMARY KEY AUTOINCREMENT,
  key TEXT NOT NULL UNIQUE, job_id TEXT NOT NULL, kind INTEGER NOT NULL,
  payload BLOB NOT NULL, state INTEGER NOT NULL DEFAULT 0,
  attempt INTEGER NOT NULL DEFAULT 0, expiries INTEGER NOT NULL DEFAULT 0,
  completions INTEGER NOT NULL DEFAULT 0, fenced INTEGER NOT NULL DEFAULT 0,
  not_before_ms INTEGER NOT NULL DEFAULT 0, sample_valid INTEGER NOT NULL DEFAULT -1,
  result BLOB);
CREATE TABLE IF NOT EXISTS task_affinity (
  worker_id TEXT NOT NULL, rank INTEGER NOT NULL, task_seq INTEGER NOT NULL,
  PRIMARY KEY (worker_id, rank, task_seq));
CREATE INDEX IF NOT EXISTS task_affinity_task ON task_affinity (task_seq);
CREATE INDEX IF NOT EXISTS tasks_of_job ON tasks (job_id);
CREATE TABLE IF NOT EXISTS leases (
  lease_id TEXT PRIMARY KEY, task_key TEXT NOT NULL, attempt INTEGER NOT NULL,
  worker_id TEXT NOT NULL, granted_ms INTEGER NOT NULL, deadline_ms INTEGER NOT NULL,
  state TEXT NOT NULL DEFAULT 'active');
CREATE INDEX IF NOT EXISTS leases_due ON leases (deadline_ms) WHERE state = 'active';
CREATE INDEX IF NOT EXISTS leases_of_worker ON leases (worker_id) WHERE state = 'active';
CREATE TABLE IF NOT EXISTS workers (
  id TEXT PRIMARY KEY, slots INTEGER NOT NULL, first_seen_ms INTEGER NOT NULL,
  last_seen_ms INTEGER NOT NULL);
CREATE TABLE IF NOT EXISTS subtrees (
  job_id TEXT NOT NULL, key TEXT NOT NULL, topology TEXT NOT NULL, op TEXT NOT NULL,
  digest TEXT NOT NULL DEFAULT '', bytes INTEGER NOT NULL, children TEXT NOT NULL,
  seconds_sum REAL NOT NULL DEFAULT 0, seconds_count INTEGER NOT NULL DEFAULT 0,
  last_seconds REAL NOT NULL DEFAULT 0, uses INTEGER NOT NULL DEFAULT 0,
  PRIMARY KEY (job_id, key));
CREATE TABLE IF NOT EXISTS sample_subtrees (
  task_key TEXT NOT NULL, position INTEGER NOT NULL, job_id TEXT NOT NULL,
  point_key TEXT NOT NULL, subtree_key TEXT NOT NULL, PRIMARY KEY (task_key, position));
CREATE INDEX IF NOT EXISTS sample_subtrees_job ON sample_subtrees (job_id);
CREATE TABLE IF NOT EXISTS job_blobs (
  job_id TEXT NOT NULL, digest TEXT NOT NULL, PRIMARY KEY (job_id, digest));
CREATE TABLE IF NOT EXISTS events (
  id INTEGER PRIMARY KEY AUTOINCREMENT, time_ms INTEGER NOT NULL, job_id TEXT NOT NULL,
  kind TEXT NOT NULL, message TEXT NOT NULL);
)sql";

}  // namespace

struct JobStore::Db {
  sqlite3* handle = nullptr;
  std::string path;
  // Prepared statements by SQL text, reused across calls (preparing costs
  // more than running most of them); the flag marks one in use.
  std::map<std::string, std::pair<sqlite3_stmt*, bool>> statements;

  void Close() {
    for (auto& [sql, entry] : statements) sqlite3_finalize(entry.first);
    statements.clear();
    if (handle) sqlite3_close(handle);
    handle = nullptr;
  }

  [[noreturn]] void Fail(const std::string& what) const {
    throw ResourceError(path + ": " + what + ": " + sqlite3_errmsg(handle));
  }
  void Exec(const char* sql) {
    char* message = nullptr;
    if (sqlite3_exec(handle, sql, nullptr, nullptr, &message) != SQLITE_OK) {
      std::string text = message ? message : "error";
      sqlite3_free(message);
      throw ResourceError(path + ": " + text);
    }
  }
};

namespace {

// A statement from the store's cache of prepared statements (preparing
// costs more than running most of them); a fresh one, finalised after use,
// when the cached one is in use further up the stack.
class Stmt : public sqlite::Statement {
 public:
  Stmt(JobStore::Db& db, const char* sql) : Stmt(db, sql, Borrow(db, sql)) {}

 private:
  Stmt(JobStore::Db& db, const char* sql, bool* in_use)
      : Statement(db.handle, sql, [&db](const std::string& what) { db.Fail(what); },
                        in_use ? db.statements.at(sql).first : nullptr,
                        in_use ? std::function<void()>([in_use] { *in_use = false; }) : nullptr) {}
  // The cached statement for `sql`, prepared on first use, marked in use;
  // nullptr when it is in use already.
  static bool* Borrow(JobStore::Db& db, const char* sql) {
    auto it = db.statements.find(sql);
    if (it == db.statements.end()) {
      sqlite3_stmt* stmt = nullptr;
      if (sqlite3_prepare_v2(db.handle, sql, -1, &stmt, nullptr) != SQLITE_OK) db.Fail("prepare");
      it = db.statements.emplace(sql, std::make_pair(stmt, false)).first;
    }
    if (it->second.second) return nullptr;
    it->second.second = true;
    return &it->second.second;
  }
};

// BEGIN IMMEDIATE ... COMMIT, rolled back if an exception escapes. A
// deferred one begins at its first Begin() (reads before it need none: the
// store's one connection is its only writer and mutex_ is held), and
// commits nothing when it never began.
class Transaction {
 public:
  struct Deferred {};
  explicit Transaction(JobStore::Db& db) : db_(db) { Begin(); }
  Transaction(JobStore::Db& db, Deferred) : db_(db) {}
  ~Transaction() {
    if (begun_ && !done_) sqlite3_exec(db_.handle, "ROLLBACK", nullptr, nullptr, nullptr);
  }
  // BEGIN and COMMIT as cached statements: sqlite3_exec parsed them again
  // for each of a job's hundreds of Syncs.
  void Begin() {
    if (begun_) return;
    Stmt(db_, "BEGIN IMMEDIATE").Run();
    begun_ = true;
  }
  void Commit() {
    if (begun_) Stmt(db_, "COMMIT").Run();
    done_ = true;
  }

 private:
  JobStore::Db& db_;
  bool begun_ = false, done_ = false;
};

// A job row: the columns of kJobColumns, in their order.
constexpr const char* kJobColumns =
    "SELECT id, bundle_digest, design_name, state, error, created_ms, finished_ms FROM jobs ";
JobRecord ReadJob(const sqlite::Statement& s) {
  JobRecord j;
  j.id = s.ColumnText(0);
  j.bundle_digest = s.ColumnText(1);
  j.design_name = s.ColumnText(2);
  j.state = static_cast<JobState>(s.ColumnInt(3));
  j.error = s.ColumnText(4);
  j.created_ms = s.ColumnInt(5);
  j.finished_ms = s.ColumnInt(6);
  return j;
}

// A lease's id: the task's seq as 16 hex digits, then the attempt. Ids in
// the order leases are granted put each new row of the leases primary key
// index beside the last one (an id from the task key's first digits, as
// before, landed on a random page of it: 2,064 of the 10,620 pages a 1k tube
// job wrote to the WAL). Unique per store, as the seq is; opaque to
// workers, so ids of the earlier form in a store still work.
std::string LeaseIdOf(std::int64_t task_seq, std::int64_t attempt) {
  char seq[17];
  std::snprintf(seq, sizeof seq, "%016llx", static_cast<unsigned long long>(task_seq));
  return std::string(seq) + "." + std::to_string(attempt);
}

// A job's task counts by a scan of its tasks (or of all tasks for "").
TaskCounts ScanCounts(JobStore::Db& db, const std::string& job_id) {
  std::string where = job_id.empty() ? "" : " WHERE job_id = ?";
  Stmt s(db, ("SELECT state, COUNT(*), SUM(sample_valid = 1), SUM(sample_valid >= 0), "
              "SUM(expiries), SUM(fenced) FROM tasks" + where + " GROUP BY state").c_str());
  if (!job_id.empty()) s.BindText(1, job_id);
  TaskCounts c;
  while (s.Next()) {
    std::int64_t n = s.ColumnInt(1);
    c.total += n;
    switch (static_cast<TaskState>(s.ColumnInt(0))) {
      case TaskState::kQueued: c.queued += n; break;
      case TaskState::kLeased: c.leased += n; break;
      case TaskState::kDone: c.done += n; break;
      case TaskState::kQuarantined: c.quarantined += n; break;
    }
    if (s.ColumnInt(0) >= 2) {
      c.samples_valid += s.ColumnInt(2);
      c.samples_done += s.ColumnInt(3);
    }
    c.lease_expiries += s.ColumnInt(4);
    c.fenced_results += s.ColumnInt(5);
  }
  return c;
}

std::int64_t& CountOf(TaskCounts& c, TaskState state) {
  switch (state) {
    case TaskState::kQueued: return c.queued;
    case TaskState::kLeased: return c.leased;
    case TaskState::kDone: return c.done;
    case TaskState::kQuarantined: break;
  }
  return c.quarantined;
}

// The changes one transaction makes to its jobs' task counts, applied to the
// counts kept in memory (JobStore::counts_) once it commits: a transaction
// rolled back moves nothing.
class CountDeltas {
 public:
  // A new task (queued).
  void Added(const std::string& job_id) {
    ++deltas_[job_id].total;
    ++deltas_[job_id].queued;
  }
  void Moved(const std::string& job_id, TaskState from, TaskState to) {
    TaskCounts& d = deltas_[job_id];
    --CountOf(d, from);
    ++CountOf(d, to);
  }
  // A sample task finished (done or quarantined), valid or not.
  void Sampled(const std::string& job_id, bool valid) {
    ++deltas_[job_id].samples_done;
    if (valid) ++deltas_[job_id].samples_valid;
  }
  void Expired(const std::string& job_id) { ++deltas_[job_id].lease_expiries; }
  void Fenced(const std::string& job_id) { ++deltas_[job_id].fenced_results; }

  void ApplyTo(std::map<std::string, TaskCounts>& counts) const {
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

 private:
  std::map<std::string, TaskCounts> deltas_;
};

constexpr int kSampleKind = 1;  // fabatlas.v1.TASK_KIND_SAMPLE

}  // namespace

JobStore::JobStore(const std::filesystem::path& path, JobStoreOptions options)
    : path_(path), options_(options), db_(std::make_unique<Db>()) {
  db_->path = path.string();
  std::error_code ec;
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path(), ec);
  if (sqlite3_open_v2(db_->path.c_str(), &db_->handle,
                      SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX,
                      nullptr) != SQLITE_OK) {
    std::string message = db_->handle ? sqlite3_errmsg(db_->handle) : "cannot open";
    sqlite3_close(db_->handle);
    db_->handle = nullptr;
    throw ResourceError(db_->path + ": cannot open the job store: " + message);
  }
  sqlite3_busy_timeout(db_->handle, 10000);
  try {
    // Schema version (user_version): refuse a store a newer coordinator
    // wrote before touching it; 0 is a store from before versions existed.
    int version = 0;
    {
      sqlite3_stmt* v = nullptr;
      sqlite3_prepare_v2(db_->handle, "PRAGMA user_version", -1, &v, nullptr);
      if (v && sqlite3_step(v) == SQLITE_ROW) version = sqlite3_column_int(v, 0);
      sqlite3_finalize(v);
    }
    if (version > kJobStoreSchemaVersion)
      throw InputError(db_->path + ": job store written by a newer fabatlas (schema version " +
                       std::to_string(version) + "; this coordinator knows versions up to " +
                       std::to_string(kJobStoreSchemaVersion) + ")");
    db_->Exec("PRAGMA journal_mode=WAL");
    db_->Exec(options_.fsync_every_commit ? "PRAGMA synchronous=FULL" : "PRAGMA synchronous=NORMAL");
    if (options_.background_checkpoints) sqlite3_wal_autocheckpoint(db_->handle, 0);
    // When a commit starts the WAL over (after a checkpoint RESTART,
    // Checkpoint()), a file grown past 16 MiB while checkpoints could not
    // keep up is cut back to 16 MiB: the WAL reuses its pages without keeping
    // its high-water mark on disk (without the limit a 10k tube job's state
    // peak was 82 MB instead of 58-62). 16 rather than the restart's 8 MiB:
    // a checkpoint comes once a second, so the WAL passes 8 MiB by up to a
    // second of commits, and cutting those pages off at every restart would
    // make the next pass extend the file again.
    db_->Exec("PRAGMA journal_size_limit = 16777216");
    db_->Exec(kSchema);
    // Stores made before lease affinity lack tasks.affine (1 while the task
    // has task_affinity rows).
    bool has_affine = false;
    {
      sqlite3_stmt* info = nullptr;
      sqlite3_prepare_v2(db_->handle, "PRAGMA table_info(tasks)", -1, &info, nullptr);
      while (info && sqlite3_step(info) == SQLITE_ROW)
        if (std::string(reinterpret_cast<const char*>(sqlite3_column_text(info, 1))) == "affine") has_affine = true;
      sqlite3_finalize(info);
    }
    if (!has_affine) db_->Exec("ALTER TABLE tasks ADD COLUMN affine INTEGER NOT NULL DEFAULT 0");
    // Indexes that a task's or a lease's change of state does not move
    // through: each commit writes every page it changed to the WAL, and a
    // Sync's results and grants once touched the tasks_job (job_id, state),
    // tasks_neutral (state, affine, seq), leases_active (state, deadline_ms)
    // and leases_worker (worker_id, state) indexes twice per row (a delete in
    // one state's range, an insert in the next): 3,600 of the 14,100 pages
    // written on the 1k tube job. Now the queue and the active leases are
    // partial indexes (small, the same few pages each commit, a finished
    // row leaves them), and a job's tasks are indexed by job alone. The
    // queries name state = 0 / state = 'active' literally, as partial
    // indexes need. Stores of earlier versions get them here; an earlier
    // coordinator opening this store adds its own back (IF NOT EXISTS).
    db_->Exec("CREATE INDEX IF NOT EXISTS tasks_queued ON tasks (affine, seq) WHERE state = 0");
    db_->Exec("DROP INDEX IF EXISTS tasks_neutral");
    db_->Exec("DROP INDEX IF EXISTS tasks_state");
    db_->Exec("DROP INDEX IF EXISTS tasks_job");
    db_->Exec("DROP INDEX IF EXISTS leases_active");
    db_->Exec("DROP INDEX IF EXISTS leases_worker");
    if (version < kJobStoreSchemaVersion)
      db_->Exec(("PRAGMA user_version = " + std::to_string(kJobStoreSchemaVersion)).c_str());
    sqlite3_stmt* count = nullptr;
    sqlite3_prepare_v2(db_->handle, "SELECT COUNT(*) FROM tasks WHERE affine = 1", -1, &count, nullptr);
    if (count && sqlite3_step(count) == SQLITE_ROW) preferring_tasks_ = sqlite3_column_int64(count, 0);
    sqlite3_finalize(count);
  } catch (const ResourceError& e) {
    // Not a database, or a corrupt one: no restart makes it one (bad input,
    // exit 2 in the coordinator); an I/O error or a full disk may pass.
    const int code = sqlite3_errcode(db_->handle) & 0xff;
    sqlite3_close(db_->handle);
    db_->handle = nullptr;
    if (code == SQLITE_NOTADB || code == SQLITE_CORRUPT) throw InputError(e.what());
    throw;
  } catch (...) {
    sqlite3_close(db_->handle);
    db_->handle = nullptr;
    throw;
  }
}

JobStore::~JobStore() {
  if (checkpoint_db_) checkpoint_db_->Close();
  if (db_) db_->Close();
}

void JobStore::Sync() {
  std::lock_guard lock(mutex_);
  // Nothing committed since the last Sync: nothing to make durable (an idle
  // coordinator's periodic blob collection costs no fsync).
  const std::int64_t changes = sqlite3_total_changes64(db_->handle);
  if (changes == synced_changes_) return;
  // The WAL's file (SQLITE_FCNTL_JOURNAL_POINTER): with synchronous=NORMAL
  // SQLite syncs it only at checkpoints, and a commit is durable once its
  // frames are (SQLite, "Write-Ahead Logging", docs/references.md).
  sqlite3_file* wal = nullptr;
  if (sqlite3_file_control(db_->handle, "main", SQLITE_FCNTL_JOURNAL_POINTER, &wal) != SQLITE_OK)
    db_->Fail("find the write-ahead log");
  if (!wal || !wal->pMethods) {  // no WAL open: every commit is in the database file, synced
    synced_changes_ = changes;
    return;
  }
  if (wal->pMethods->xSync(wal, SQLITE_SYNC_NORMAL) != SQLITE_OK)
    throw ResourceError(db_->path + "-wal: cannot sync the write-ahead log");
  synced_changes_ = changes;
}

int JobStore::Checkpoint() {
  std::lock_guard lock(checkpoint_mutex_);
  if (!checkpoint_db_) {
    auto db = std::make_unique<Db>();
    db->path = db_->path;
    if (sqlite3_open_v2(db->path.c_str(), &db->handle, SQLITE_OPEN_READWRITE | SQLITE_OPEN_FULLMUTEX, nullptr) !=
        SQLITE_OK) {
      std::string message = db->handle ? sqlite3_errmsg(db->handle) : "cannot open";
      sqlite3_close(db->handle);
      throw ResourceError(db->path + ": cannot open the job store for checkpoints: " + message);
    }
    sqlite3_busy_timeout(db->handle, 1000);
    db->Exec(options_.fsync_every_commit ? "PRAGMA synchronous=FULL" : "PRAGMA synchronous=NORMAL");
    checkpoint_db_ = std::move(db);
  }
  int log = 0, done = 0;
  int rc = sqlite3_wal_checkpoint_v2(checkpoint_db_->handle, nullptr, SQLITE_CHECKPOINT_PASSIVE, &log, &done);
  if (rc != SQLITE_OK && rc != SQLITE_BUSY) checkpoint_db_->Fail("checkpoint");
  // Under a steady stream of commits a passive checkpoint never catches up
  // with the last frame, so the WAL never restarts and grows with the job
  // (61 MB on a 2k-sample job). Past kWalRestartFrames (8 MiB of 4 KiB
  // pages), a RESTART checkpoint waits (busy timeout) for the writer, copies
  // the rest, and the next commit writes from the WAL's start again: the WAL
  // stays bounded whatever the job's size. RESTART rather than TRUNCATE: the
  // file keeps its pages, so commits overwrite pages the kernel has cached
  // instead of extending an emptied file (a new page cache page and a block
  // reservation per frame: about half the cost of the WAL writes on the 1k
  // tube job).
  constexpr int kWalRestartFrames = 2048;
  if (log > kWalRestartFrames) {
    rc = sqlite3_wal_checkpoint_v2(checkpoint_db_->handle, nullptr, SQLITE_CHECKPOINT_RESTART, &log, &done);
    if (rc != SQLITE_OK && rc != SQLITE_BUSY) checkpoint_db_->Fail("checkpoint");
  }
  return done;
}

bool JobStore::CreateJob(const JobRecord& job) {
  std::lock_guard lock(mutex_);
  Stmt s(*db_,
         "INSERT OR IGNORE INTO jobs (id, bundle_digest, design_name, state, error, created_ms, "
         "finished_ms) VALUES (?,?,?,?,?,?,?)");
  s.BindText(1, job.id).BindText(2, job.bundle_digest).BindText(3, job.design_name);
  s.Bind(4, static_cast<std::int64_t>(job.state)).BindText(5, job.error);
  s.Bind(6, job.created_ms).Bind(7, job.finished_ms);
  s.Run();
  return sqlite3_changes(db_->handle) == 1;
}

std::optional<JobRecord> JobStore::FindJob(const std::string& id) {
  std::lock_guard lock(mutex_);
  Stmt s(*db_, (std::string(kJobColumns) + "WHERE id = ?").c_str());
  s.BindText(1, id);
  if (!s.Next()) return std::nullopt;
  return ReadJob(s);
}

std::vector<JobRecord> JobStore::Jobs() {
  std::lock_guard lock(mutex_);
  Stmt s(*db_, (std::string(kJobColumns) + "ORDER BY created_ms, id").c_str());
  return s.Rows(ReadJob);
}

void JobStore::SetJobState(const std::string& id, JobState state, const std::string& error,
                           std::int64_t finished_ms) {
  std::lock_guard lock(mutex_);
  Stmt s(*db_, "UPDATE jobs SET state = ?, error = ?, finished_ms = ? WHERE id = ?");
  s.Bind(1, static_cast<std::int64_t>(state)).BindText(2, error).Bind(3, finished_ms).BindText(4, id);
  s.Run();
}

void JobStore::PutJobOutput(const std::string& job_id, const std::string& name,
                            const std::string& digest) {
  std::lock_guard lock(mutex_);
  Stmt s(*db_, "INSERT OR REPLACE INTO job_outputs (job_id, name, digest) VALUES (?,?,?)");
  s.BindText(1, job_id).BindText(2, name).BindText(3, digest);
  s.Run();
}

std::map<std::string, std::string> JobStore::JobOutputs(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  Stmt s(*db_, "SELECT name, digest FROM job_outputs WHERE job_id = ? ORDER BY name");
  s.BindText(1, job_id);
  std::map<std::string, std::string> out;
  while (s.Next()) out[s.ColumnText(0)] = s.ColumnText(1);
  return out;
}

std::map<std::string, std::string> JobStore::AddTasks(const std::vector<NewTask>& tasks) {
  std::lock_guard lock(mutex_);
  Transaction t(*db_);
  Stmt insert(*db_, "INSERT OR IGNORE INTO tasks (key, job_id, kind, payload, affine) VALUES (?,?,?,?,?)");
  Stmt find(*db_, "SELECT result FROM tasks WHERE key = ? AND state IN (2, 3)");
  Stmt prefer(*db_, "INSERT OR IGNORE INTO task_affinity (worker_id, rank, task_seq) VALUES (?,?,?)");
  std::map<std::string, std::string> finished;
  CountDeltas deltas;
  std::int64_t preferring = 0;
  for (const NewTask& task : tasks) {
    insert.BindText(1, task.key).BindText(2, task.job_id).Bind(3, std::int64_t{task.kind});
    insert.Bind(4, task.payload).Bind(5, std::int64_t{task.preferred_workers.empty() ? 0 : 1});
    insert.Run();
    insert.Reset();
    const bool inserted = sqlite3_changes(db_->handle) == 1;
    if (inserted) deltas.Added(task.job_id);
    if (!task.preferred_workers.empty() && inserted) {
      // rank: how many workers share the preference (fewer = more this worker's own)
      std::int64_t seq = sqlite3_last_insert_rowid(db_->handle);
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

namespace {
constexpr const char* kTaskColumns =
    "SELECT key, job_id, kind, payload, state, attempt, expiries, completions, result FROM tasks ";
TaskRecord ReadTask(const sqlite::Statement& s) {
  TaskRecord r;
  r.key = s.ColumnText(0);
  r.job_id = s.ColumnText(1);
  r.kind = static_cast<int>(s.ColumnInt(2));
  r.payload = s.ColumnText(3);
  r.state = static_cast<TaskState>(s.ColumnInt(4));
  r.attempt = s.ColumnInt(5);
  r.expiries = s.ColumnInt(6);
  r.completions = s.ColumnInt(7);
  r.result = s.ColumnText(8);
  return r;
}
}  // namespace

std::optional<TaskRecord> JobStore::FindTask(const std::string& key) {
  std::lock_guard lock(mutex_);
  Stmt s(*db_, (std::string(kTaskColumns) + "WHERE key = ?").c_str());
  s.BindText(1, key);
  if (!s.Next()) return std::nullopt;
  return ReadTask(s);
}

std::vector<TaskRecord> JobStore::Tasks(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  Stmt s(*db_, (std::string(kTaskColumns) + "WHERE job_id = ? ORDER BY seq").c_str());
  s.BindText(1, job_id);
  return s.Rows(ReadTask);
}

namespace {

// Complete's work inside the caller's transaction (begun).
std::vector<CompletionOutcome> CompleteIn(JobStore::Db& db, const std::vector<Completion>& completions,
                                          std::int64_t now_ms, std::int64_t retry_backoff_ms, int quarantine_after,
                                          const std::function<std::string(int kind)>& quarantine_result,
                                          CountDeltas& deltas) {
  std::vector<CompletionOutcome> outcomes;
  Stmt task(db, "SELECT state, attempt, job_id, kind FROM tasks WHERE key = ?");
  Stmt lease(db, "SELECT state FROM leases WHERE lease_id = ? AND task_key = ? AND attempt = ?");
  Stmt subtree(db,
               "INSERT INTO subtrees (job_id, key, topology, op, digest, bytes, children, seconds_sum, "
               "seconds_count, last_seconds, uses) VALUES (?,?,?,?,?,?,?,?,?,?,1) "
               "ON CONFLICT (job_id, key) DO UPDATE SET "
               "digest = CASE WHEN digest = '' THEN excluded.digest ELSE digest END, "
               "seconds_sum = seconds_sum + excluded.seconds_sum, "
               "seconds_count = seconds_count + excluded.seconds_count, "
               "last_seconds = excluded.last_seconds, uses = uses + 1");
  Stmt use(db,
           "INSERT OR IGNORE INTO sample_subtrees (task_key, position, job_id, point_key, subtree_key) "
           "VALUES (?,?,?,?,?)");
  Stmt set_lease(db, "UPDATE leases SET state = ? WHERE lease_id = ? AND state = 'active'");
  Stmt done(db,
            "UPDATE tasks SET state = 2, result = ?, completions = completions + 1, "
            "sample_valid = ? WHERE key = ?");
  Stmt fenced(db, "UPDATE tasks SET fenced = fenced + 1 WHERE key = ?");
  Stmt requeue(db, "UPDATE tasks SET state = 0, not_before_ms = ? WHERE key = ?");
  Stmt failures(db,
                "SELECT COUNT(*), COUNT(DISTINCT worker_id) FROM leases WHERE task_key = ? AND "
                "(state = 'failed' OR lease_id = ?)");
  Stmt quarantine(db,
                  "UPDATE tasks SET state = 3, result = ?, completions = completions + 1, "
                  "sample_valid = CASE WHEN kind = 1 THEN 0 ELSE -1 END WHERE key = ?");
  Stmt event(db, "INSERT INTO events (time_ms, job_id, kind, message) VALUES (?,?,?,?)");
  for (const Completion& c : completions) {
    task.BindText(1, c.task_key);
    if (!task.Next()) {
      task.Reset();
      outcomes.push_back(CompletionOutcome::kUnknown);
      continue;
    }
    auto state = static_cast<TaskState>(task.ColumnInt(0));
    std::int64_t attempt = task.ColumnInt(1);
    std::string job_id = task.ColumnText(2);
    const int kind = static_cast<int>(task.ColumnInt(3));
    task.Reset();
    lease.BindText(1, c.lease_id).BindText(2, c.task_key).Bind(3, c.attempt);
    bool active = lease.Next() && lease.ColumnText(0) == "active";
    lease.Reset();
    CompletionOutcome outcome;
    std::string lease_state;
    if (state == TaskState::kDone || state == TaskState::kQuarantined) {
      outcome = CompletionOutcome::kDuplicate;
      lease_state = "duplicate";
    } else if (!active || state != TaskState::kLeased || c.attempt != attempt) {
      outcome = CompletionOutcome::kFenced;
      lease_state = "fenced";
      fenced.BindText(1, c.task_key);
      fenced.Run();
      fenced.Reset();
      deltas.Fenced(job_id);
    } else if (c.failed) {
      lease_state = "failed";
      failures.BindText(1, c.task_key).BindText(2, c.lease_id);
      failures.Next();
      const std::int64_t failed_leases = failures.ColumnInt(0), failed_workers = failures.ColumnInt(1);
      failures.Reset();
      std::string kind_name = "task_failed";
      if (quarantine_after > 0 && quarantine_result && failed_workers >= quarantine_after) {
        outcome = CompletionOutcome::kQuarantined;
        kind_name = "quarantined";
        quarantine.Bind(1, quarantine_result(kind)).BindText(2, c.task_key);
        quarantine.Run();
        quarantine.Reset();
        deltas.Moved(job_id, TaskState::kLeased, TaskState::kQuarantined);
        if (kind == kSampleKind) deltas.Sampled(job_id, false);
      } else {
        outcome = CompletionOutcome::kRequeued;
        std::int64_t delay = retry_backoff_ms << std::min<std::int64_t>(std::max<std::int64_t>(failed_leases - 1, 0), 20);
        requeue.Bind(1, now_ms + std::min<std::int64_t>(delay, 30000)).BindText(2, c.task_key);
        requeue.Run();
        requeue.Reset();
        deltas.Moved(job_id, TaskState::kLeased, TaskState::kQueued);
      }
      event.Bind(1, now_ms).BindText(2, job_id).BindText(3, kind_name);
      event.BindText(4, "task " + c.task_key.substr(0, 16) + " lease " + c.lease_id + " failed (" +
                            std::to_string(failed_workers) + " worker(s) so far): " +
                            (c.error.empty() ? std::string("no reason given") : c.error));
      event.Run();
      event.Reset();
    } else {
      outcome = CompletionOutcome::kAccepted;
      lease_state = "completed";
      done.Bind(1, c.result).Bind(2, std::int64_t{c.sample_valid}).BindText(3, c.task_key);
      done.Run();
      done.Reset();
      deltas.Moved(job_id, TaskState::kLeased, TaskState::kDone);
      if (c.sample_valid >= 0) deltas.Sampled(job_id, c.sample_valid == 1);
      std::int64_t position = 0;
      for (const SubtreeUse& u : c.subtrees) {
        const std::string children = KeyListText(u.children);
        subtree.BindText(1, job_id).BindText(2, u.key).BindText(3, u.topology).BindText(4, u.op);
        subtree.BindText(5, u.blob_digest).Bind(6, u.bytes).BindText(7, children);
        subtree.BindReal(8, u.measured ? u.seconds : 0.0).Bind(9, std::int64_t{u.measured ? 1 : 0});
        subtree.BindReal(10, u.seconds);
        subtree.Run();
        subtree.Reset();
        use.BindText(1, c.task_key).Bind(2, position++).BindText(3, job_id).BindText(4, c.point_key);
        use.BindText(5, u.key);
        use.Run();
        use.Reset();
      }
    }
    set_lease.BindText(1, lease_state).BindText(2, c.lease_id);
    set_lease.Run();
    set_lease.Reset();
    outcomes.push_back(outcome);
  }
  return outcomes;
}

// GrantLeases' choice of tasks, by reads only (so an empty queue costs no
// write transaction): up to `max` grants, of them up to `steal` preferring
// other workers (all when negative); unprefer gets the seq of granted tasks
// that had a preference. any_preferring: some task prefers a worker.
std::vector<LeaseGrant> PickLeases(JobStore::Db& db, const std::string& worker_id, int max, int steal,
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
  auto take = [&](Stmt& pick, int cap) {  // until `cap` grants in all
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
    Stmt pick(db, own.c_str());
    pick.BindText(1, worker_id).Bind(2, now_ms).Bind(3, std::int64_t{max});
    take(pick, max);
  }
  if (static_cast<int>(grants.size()) < max) {
    Stmt pick(db, neutral.c_str());
    pick.Bind(1, now_ms).Bind(2, std::int64_t{max - static_cast<int>(grants.size())});
    take(pick, max);
  }
  // Never skipped while the worker has an idle slot: no preferred task can
  // starve. Own preferred tasks were all taken above and may come again here.
  const int before = static_cast<int>(grants.size());
  const int limit = steal < 0 ? max : std::min(max, before + steal);
  if (before < limit) {
    Stmt pick(db, others.c_str());
    pick.Bind(1, now_ms).Bind(2, std::int64_t{limit - before + static_cast<int>(unprefer.size())});
    take(pick, limit);
  }
  return grants;
}

// Writes picked grants (PickLeases) inside the caller's transaction (begun):
// tasks leased, lease rows, preferences of the granted tasks dropped.
void WriteLeasesIn(JobStore::Db& db, const std::string& worker_id, std::int64_t now_ms,
                   const std::vector<LeaseGrant>& grants, const std::vector<std::int64_t>& unprefer,
                   CountDeltas& deltas) {
  Stmt update(db, "UPDATE tasks SET state = 1, attempt = ? WHERE key = ?");
  Stmt lease(db,
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
    Stmt drop(db, "DELETE FROM task_affinity WHERE task_seq = ?");
    Stmt neutral_again(db, "UPDATE tasks SET affine = 0 WHERE seq = ?");
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
  // page into nearly every commit's WAL frames (356 of 9,256 on the 1k tube
  // job).
}

// A worker's active lease.
struct ActiveLease {
  std::string lease_id, task_key, job_id;
  std::int64_t deadline_ms = 0;
};

// The worker's active leases (one read, shared by ReturnUnknownLeases and
// ExtendLeases).
std::vector<ActiveLease> ActiveLeasesOf(JobStore::Db& db, const std::string& worker_id) {
  Stmt s(db,
         "SELECT l.lease_id, l.task_key, t.job_id, l.deadline_ms FROM leases l JOIN tasks t ON t.key = l.task_key "
         "WHERE l.worker_id = ? AND l.state = 'active'");
  s.BindText(1, worker_id);
  return s.Rows([](const sqlite::Statement& row) {
    return ActiveLease{row.ColumnText(0), row.ColumnText(1), row.ColumnText(2), row.ColumnInt(3)};
  });
}

// ReturnUnknownLeases: the active leases not in `known` go back to the
// queue, inside `t` (begun when there is one). Returns how many.
int ReturnUnknownIn(JobStore::Db& db, Transaction& t, const std::vector<ActiveLease>& active,
                    const std::vector<std::string>& known, CountDeltas& deltas) {
  std::set<std::string> keep(known.begin(), known.end());
  int returned = 0;
  for (const ActiveLease& l : active) {
    if (keep.count(l.lease_id)) continue;
    t.Begin();
    Stmt lease(db, "UPDATE leases SET state = 'returned' WHERE lease_id = ?");
    lease.BindText(1, l.lease_id);
    lease.Run();
    Stmt task(db, "UPDATE tasks SET state = 0 WHERE key = ? AND state = 1");
    task.BindText(1, l.task_key);
    task.Run();
    if (sqlite3_changes(db.handle) == 1) deltas.Moved(l.job_id, TaskState::kLeased, TaskState::kQueued);
    ++returned;
  }
  return returned;
}

// ExtendLeases inside `t` (begun only when a deadline moves): the listed
// ids that are active leases due before deadline_ms - slack_ms move to
// deadline_ms; returns the listed ids that are not active leases.
std::vector<std::string> ExtendIn(JobStore::Db& db, Transaction& t, const std::string& worker_id,
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
    Stmt s(db,
           "UPDATE leases SET deadline_ms = MAX(deadline_ms, ?) WHERE lease_id = ? AND worker_id = ? "
           "AND state = 'active'");
    s.Bind(1, deadline_ms).BindText(2, id).BindText(3, worker_id);
    s.Run();
  }
  return revoked;
}

}  // namespace

std::vector<LeaseGrant> JobStore::GrantLeases(const std::string& worker_id, int max,
                                              std::int64_t now_ms, std::int64_t lease_ms, int steal) {
  std::lock_guard lock(mutex_);
  std::vector<std::int64_t> unprefer;
  std::vector<LeaseGrant> grants = PickLeases(*db_, worker_id, max, steal, now_ms, lease_ms, preferring_tasks_ > 0, unprefer);
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
    Stmt s(*db_, "SELECT task_seq FROM task_affinity WHERE worker_id = ?");
    s.BindText(1, worker_id);
    while (s.Next()) seqs.push_back(s.ColumnInt(0));
  }
  if (seqs.empty()) return 0;
  Transaction t(*db_);
  Stmt drop(*db_, "DELETE FROM task_affinity WHERE worker_id = ?");
  drop.BindText(1, worker_id);
  drop.Run();
  Stmt neutral_again(*db_,
                     "UPDATE tasks SET affine = 0 WHERE seq = ? AND affine = 1 AND NOT EXISTS (SELECT 1 FROM task_affinity a "
                     "WHERE a.task_seq = ?)");
  int lost = 0;
  for (std::int64_t seq : seqs) {
    neutral_again.Bind(1, seq).Bind(2, seq);
    neutral_again.Run();
    lost += sqlite3_changes(db_->handle);
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

std::vector<CompletionOutcome> JobStore::Complete(const std::vector<Completion>& completions,
                                                  std::int64_t now_ms, std::int64_t retry_backoff_ms,
                                                  int quarantine_after,
                                                  const std::function<std::string(int kind)>& quarantine_result) {
  if (completions.empty()) return {};
  std::lock_guard lock(mutex_);
  Transaction t(*db_);
  CountDeltas deltas;
  auto outcomes = CompleteIn(*db_, completions, now_ms, retry_backoff_ms, quarantine_after, quarantine_result, deltas);
  t.Commit();
  deltas.ApplyTo(counts_);
  return outcomes;
}

std::vector<std::string> JobStore::ExtendLeases(const std::string& worker_id,
                                                const std::vector<std::string>& lease_ids,
                                                std::int64_t deadline_ms, std::int64_t slack_ms) {
  if (lease_ids.empty()) return {};
  std::lock_guard lock(mutex_);
  // Read first: a Sync that lists leases extended moments ago writes nothing.
  Transaction t(*db_, Transaction::Deferred{});
  auto revoked = ExtendIn(*db_, t, worker_id, ActiveLeasesOf(*db_, worker_id), lease_ids, deadline_ms, slack_ms);
  t.Commit();
  return revoked;
}

int JobStore::ReturnUnknownLeases(const std::string& worker_id,
                                  const std::vector<std::string>& known) {
  std::lock_guard lock(mutex_);
  Transaction t(*db_, Transaction::Deferred{});
  CountDeltas deltas;
  const int returned = ReturnUnknownIn(*db_, t, ActiveLeasesOf(*db_, worker_id), known, deltas);
  t.Commit();
  deltas.ApplyTo(counts_);
  return returned;
}

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
  out.revoked = ExtendIn(*db_, t, sync.worker_id, active, sync.in_flight, sync.now_ms + sync.lease_ms,
                         sync.lease_ms / 2);
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

std::vector<ExpiredLease> JobStore::ExpireLeases(
    std::int64_t now_ms, std::int64_t backoff_ms, int quarantine_after,
    const std::function<std::string(int kind)>& quarantine_result) {
  std::vector<ExpiredLease> expired;
  std::lock_guard lock(mutex_);
  std::vector<std::int64_t> kinds, expiries;
  {
    Stmt s(*db_,
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
  Stmt lease(*db_, "UPDATE leases SET state = 'expired' WHERE lease_id = ?");
  Stmt requeue(*db_,
               "UPDATE tasks SET state = 0, expiries = ?, not_before_ms = ? WHERE key = ? AND "
               "state = 1");
  Stmt quarantine(*db_,
                  "UPDATE tasks SET state = 3, expiries = ?, result = ?, completions = "
                  "completions + 1, sample_valid = CASE WHEN kind = 1 THEN 0 ELSE -1 END "
                  "WHERE key = ? AND state = 1");
  Stmt event(*db_, "INSERT INTO events (time_ms, job_id, kind, message) VALUES (?,?,?,?)");
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
      if (sqlite3_changes(db_->handle) == 1) {
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
      if (sqlite3_changes(db_->handle) == 1) {
        deltas.Moved(e.job_id, TaskState::kLeased, TaskState::kQueued);
        deltas.Expired(e.job_id);
      }
    }
    event.Bind(1, now_ms).BindText(2, e.job_id).BindText(3, kind);
    event.BindText(4, "task " + e.task_key.substr(0, 16) + " lease " + e.lease_id + " of worker " +
                          e.worker_id + " expired (" + std::to_string(expiries[i]) + " so far)");
    event.Run();
    event.Reset();
  }
  t.Commit();
  deltas.ApplyTo(counts_);
  return expired;
}

void JobStore::ExtendAllLeases(std::int64_t deadline_ms) {
  std::lock_guard lock(mutex_);
  Stmt s(*db_, "UPDATE leases SET deadline_ms = MAX(deadline_ms, ?) WHERE state = 'active'");
  s.Bind(1, deadline_ms);
  s.Run();
}

TaskCounts JobStore::CountTasks(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  if (job_id.empty()) return ScanCounts(*db_, job_id);
  auto it = counts_.find(job_id);
  if (it == counts_.end()) it = counts_.emplace(job_id, ScanCounts(*db_, job_id)).first;
  return it->second;
}

std::int64_t JobStore::ActiveLeases() {
  std::lock_guard lock(mutex_);
  Stmt s(*db_, "SELECT COUNT(*) FROM leases WHERE state = 'active'");
  s.Next();
  return s.ColumnInt(0);
}

std::vector<SubtreeRow> JobStore::Subtrees(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  Stmt s(*db_,
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
  Stmt s(*db_,
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
  Stmt s(*db_, "INSERT OR IGNORE INTO job_blobs (job_id, digest) VALUES (?,?)");
  s.BindText(1, job_id).BindText(2, digest);
  s.Run();
}

std::vector<std::string> JobStore::ReferencedBlobs() {
  std::lock_guard lock(mutex_);
  // Jobs not ended: queued (1) or running (2).
  Stmt s(*db_,
         "SELECT bundle_digest FROM jobs UNION SELECT digest FROM job_outputs "
         "UNION SELECT s.digest FROM subtrees s JOIN jobs j ON j.id = s.job_id WHERE j.state IN (1, 2) "
         "AND s.digest != '' "
         "UNION SELECT b.digest FROM job_blobs b JOIN jobs j ON j.id = b.job_id WHERE j.state IN (1, 2) "
         "ORDER BY 1");
  return s.Rows([](const sqlite::Statement& row) { return row.ColumnText(0); });
}

std::int64_t JobStore::OldestActiveLeaseMs() {
  std::lock_guard lock(mutex_);
  Stmt s(*db_, "SELECT MIN(granted_ms) FROM leases WHERE state = 'active'");
  if (!s.Next() || s.ColumnIsNull(0)) return -1;
  return s.ColumnInt(0);
}

void JobStore::TouchWorker(const std::string& worker_id, int slots, std::int64_t now_ms) {
  std::lock_guard lock(mutex_);
  // At most one write per worker and second (last_seen_ms is precise to 1 s).
  auto& touched = touched_[worker_id];
  if (touched.second != 0 && touched.second <= now_ms && now_ms - touched.second < 1000) return;
  touched = {slots, now_ms};
  Stmt s(*db_,
         "INSERT INTO workers (id, slots, first_seen_ms, last_seen_ms) VALUES (?,?,?,?) "
         "ON CONFLICT(id) DO UPDATE SET slots = excluded.slots, last_seen_ms = excluded.last_seen_ms");
  s.BindText(1, worker_id).Bind(2, std::int64_t{slots}).Bind(3, now_ms).Bind(4, now_ms);
  s.Run();
}

std::int64_t JobStore::CountWorkers(std::int64_t since_ms) {
  std::lock_guard lock(mutex_);
  Stmt s(*db_, "SELECT COUNT(*) FROM workers WHERE last_seen_ms >= ?");
  s.Bind(1, since_ms);
  s.Next();
  return s.ColumnInt(0);
}

void JobStore::AddEvent(const Event& event) {
  std::lock_guard lock(mutex_);
  Stmt s(*db_, "INSERT INTO events (time_ms, job_id, kind, message) VALUES (?,?,?,?)");
  s.Bind(1, event.time_ms).BindText(2, event.job_id).BindText(3, event.kind);
  s.BindText(4, event.message);
  s.Run();
}

std::vector<Event> JobStore::Events(const std::string& job_id) {
  std::lock_guard lock(mutex_);
  Stmt s(*db_, "SELECT time_ms, job_id, kind, message FROM events WHERE job_id = ? ORDER BY id");
  s.BindText(1, job_id);
  return s.Rows([](const sqlite::Statement& row) {
    return Event{row.ColumnInt(0), row.ColumnText(1), row.ColumnText(2), row.ColumnText(3)};
  });
}

std::vector<std::string> JobStore::CheckConsistency() {
  std::lock_guard lock(mutex_);
  std::vector<std::string> problems;
  {
    Stmt s(*db_, "SELECT key, completions FROM tasks WHERE state IN (2, 3) AND completions != 1");
    while (s.Next())
      problems.push_back("task " + s.ColumnText(0) + " completed " + std::to_string(s.ColumnInt(1)) + " times");
  }
  {
    Stmt s(*db_,
           "SELECT l.lease_id FROM leases l JOIN tasks t ON t.key = l.task_key WHERE "
           "l.state = 'active' AND (t.state != 1 OR t.attempt != l.attempt)");
    while (s.Next()) problems.push_back("orphaned active lease " + s.ColumnText(0));
  }
  {
    Stmt s(*db_,
           "SELECT t.key FROM tasks t WHERE t.state = 1 AND (SELECT COUNT(*) FROM leases l WHERE "
           "l.task_key = t.key AND l.state = 'active') != 1");
    while (s.Next()) problems.push_back("leased task " + s.ColumnText(0) + " without one active lease");
  }
  {
    Stmt s(*db_, "SELECT key FROM tasks WHERE state IN (0, 1) AND completions != 0");
    while (s.Next()) problems.push_back("unfinished task " + s.ColumnText(0) + " has a result");
  }
  for (const auto& [job_id, kept] : counts_) {
    const TaskCounts scanned = ScanCounts(*db_, job_id);
    auto text = [](const TaskCounts& c) {
      return std::to_string(c.total) + " tasks (" + std::to_string(c.queued) + " queued, " +
             std::to_string(c.leased) + " leased, " + std::to_string(c.done) + " done, " +
             std::to_string(c.quarantined) + " quarantined), " + std::to_string(c.samples_done) + " samples (" +
             std::to_string(c.samples_valid) + " valid), " + std::to_string(c.lease_expiries) + " expiries, " +
             std::to_string(c.fenced_results) + " fenced";
    };
    if (text(kept) != text(scanned))
      problems.push_back("job " + job_id + " counts " + text(kept) + " in memory but " + text(scanned) + " in its tasks");
  }
  return problems;
}

}  // namespace fabatlas::storage
