// The job store's tables and their numbered migrations (see schema.h).
#include "schema.h"

#include "fabatlas/error.h"
#include "fabatlas/storage/job_store.h"

namespace fabatlas::storage::internal {

namespace {

// Migration 1: the tables, as a new store gets them (IF NOT EXISTS: a store
// from before versions existed has most of them).
constexpr const char* kTables = R"sql(
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

void CreateTables(sqlite::Connection& db) { db.Exec(kTables); }

// Migration 2: tasks.affine, 1 while the task has task_affinity rows (lease
// affinity); stores made before lease affinity lack it.
void AddTaskAffinity(sqlite::Connection& db) {
  if (db.ExecInt("SELECT COUNT(*) FROM pragma_table_info('tasks') WHERE name = 'affine'") == 0)
    db.Exec("ALTER TABLE tasks ADD COLUMN affine INTEGER NOT NULL DEFAULT 0");
}

// Migration 3: indexes that a task's or a lease's change of state does not
// move through. Each commit writes every page it changed to the WAL, and a
// Sync's results and grants once touched the tasks_job (job_id, state),
// tasks_neutral (state, affine, seq), leases_active (state, deadline_ms) and
// leases_worker (worker_id, state) indexes twice per row (a delete in one
// state's range, an insert in the next). Now the queue and the active leases
// are partial indexes (small, the same few pages each commit, a finished row
// leaves them: leases_due and leases_of_worker in kTables), and a job's
// tasks are indexed by job alone. The queries name state = 0 / state =
// 'active' literally, as partial indexes need.
void UsePartialIndexes(sqlite::Connection& db) {
  db.Exec("CREATE INDEX IF NOT EXISTS tasks_queued ON tasks (affine, seq) WHERE state = 0");
  for (const char* index : {"tasks_neutral", "tasks_state", "tasks_job", "leases_active", "leases_worker"})
    db.Exec(std::string("DROP INDEX IF EXISTS ") + index);
}

// In order; each idempotent (schema.h).
constexpr void (*kMigrations[])(sqlite::Connection&) = {CreateTables, AddTaskAffinity, UsePartialIndexes};

// A file that is not a database fails here first, with SQLite's message
// alone ("<path>: file is not a database").
int StoredVersion(sqlite::Connection& db) { return static_cast<int>(db.ExecInt("PRAGMA user_version")); }

}  // namespace

void CheckSchemaVersion(sqlite::Connection& db, const std::string& path) {
  const int version = StoredVersion(db);
  if (version > kJobStoreSchemaVersion)
    throw InputError(path + ": job store written by a newer fabatlas (schema version " + std::to_string(version) +
                     "; this coordinator knows versions up to " + std::to_string(kJobStoreSchemaVersion) + ")");
}

void MigrateSchema(sqlite::Connection& db) {
  for (auto migrate : kMigrations) migrate(db);
  if (StoredVersion(db) < kJobStoreSchemaVersion)
    db.Exec("PRAGMA user_version = " + std::to_string(kJobStoreSchemaVersion));
}

}  // namespace fabatlas::storage::internal
