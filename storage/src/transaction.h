// BEGIN IMMEDIATE ... COMMIT on the job store's connection (internal to
// storage/).
#pragma once

#include "fabatlas/sqlite/connection.h"

namespace fabatlas::storage::internal {

// Rolled back if an exception escapes before Commit(). A deferred one
// begins at its first Begin() (reads before it need none: the store's one
// connection is its only writer and JobStore::mutex_ is held), and commits
// nothing when it never began.
class Transaction {
 public:
  struct Deferred {};
  explicit Transaction(sqlite::Connection& db) : db_(db) { Begin(); }
  Transaction(sqlite::Connection& db, Deferred) : db_(db) {}
  ~Transaction() {
    if (begun_ && !done_) sqlite3_exec(db_.get(), "ROLLBACK", nullptr, nullptr, nullptr);
  }
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  // BEGIN and COMMIT as cached statements: sqlite3_exec parsed them again
  // for each of a job's hundreds of Syncs.
  void Begin() {
    if (begun_) return;
    db_.Cached("BEGIN IMMEDIATE").Run();
    begun_ = true;
  }
  void Commit() {
    if (begun_) db_.Cached("COMMIT").Run();
    done_ = true;
  }

 private:
  sqlite::Connection& db_;
  bool begun_ = false, done_ = false;
};

}  // namespace fabatlas::storage::internal
