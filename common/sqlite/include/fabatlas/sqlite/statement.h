// fabatlas/sqlite/statement.h — one prepared SQLite statement: bind its
// parameters, step through its rows, read their columns. Made by
// sqlite::Connection (connection.h: Prepare, Cached) for the job store
// (storage/) and the artifact file (artifact/); include it only from .cc
// files (it includes sqlite3.h).
//
// Bind*(i, value) sets parameter i (from 1); Column*(c) reads column c (from
// 0) of the current row. Next() steps to the next row, false at the end;
// Rows(read) collects the remaining rows, each as read(statement) makes it;
// Run() steps to the end (rows are skipped) and resets the statement for the
// next bindings; Reset() only resets. Blobs and texts are copied on binding.
// Any failing SQLite call calls `fail(what)`, which must throw (the job store
// throws ResourceError naming the store, the artifact Corrupt); SQLite's own
// message is sqlite3_errmsg(db).
//
// Threading: a statement belongs to one connection and one thread at a time.
#pragma once

#include <sqlite3.h>

#include <cstdint>
#include <cstdlib>
#include <functional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace fabatlas::sqlite {

class Statement {
 public:
  using Fail = std::function<void(const std::string& what)>;

  // Prepares `sql` on `db` and finalises it on destruction; or, given
  // `prepared` (a statement the caller keeps, e.g. in a cache of prepared
  // statements), uses that one and on destruction resets it, clears its
  // bindings and calls `release` instead.
  Statement(sqlite3* db, const std::string& sql, Fail fail, sqlite3_stmt* prepared = nullptr,
            std::function<void()> release = {})
      : db_(db), stmt_(prepared), fail_(std::move(fail)), release_(std::move(release)) {
    if (!stmt_ && sqlite3_prepare_v2(db_, sql.c_str(), -1, &stmt_, nullptr) != SQLITE_OK) Failed("prepare");
    if (!prepared) release_ = nullptr;
  }
  ~Statement() {
    if (!release_) {
      sqlite3_finalize(stmt_);
      return;
    }
    Reset();
    release_();
  }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  Statement& Bind(int i, std::int64_t v) { return Check(sqlite3_bind_int64(stmt_, i, v), "bind"); }
  Statement& BindReal(int i, double v) { return Check(sqlite3_bind_double(stmt_, i, v), "bind"); }
  Statement& BindNull(int i) { return Check(sqlite3_bind_null(stmt_, i), "bind"); }
  Statement& BindText(int i, const std::string& v) {
    return Check(sqlite3_bind_text64(stmt_, i, v.data(), v.size(), SQLITE_TRANSIENT, SQLITE_UTF8), "bind");
  }
  // Bytes as a BLOB.
  Statement& Bind(int i, const std::string& v) {
    return Check(sqlite3_bind_blob64(stmt_, i, v.data(), v.size(), SQLITE_TRANSIENT), "bind");
  }

  // True while a row is available.
  bool Next() {
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc != SQLITE_DONE) Failed("step");
    return false;
  }
  // The remaining rows in order, each as `read(*this)` makes it from the
  // current row.
  template <typename Read>
  auto Rows(Read&& read) {
    std::vector<std::decay_t<decltype(read(*this))>> out;
    while (Next()) out.push_back(read(*this));
    return out;
  }
  void Run() {
    while (Next()) {
    }
    Reset();
  }
  void Reset() {
    sqlite3_reset(stmt_);
    sqlite3_clear_bindings(stmt_);
  }

  int ColumnCount() const { return sqlite3_column_count(stmt_); }
  int ColumnType(int c) const { return sqlite3_column_type(stmt_, c); }
  bool ColumnIsNull(int c) const { return ColumnType(c) == SQLITE_NULL; }
  std::int64_t ColumnInt(int c) const { return sqlite3_column_int64(stmt_, c); }
  double ColumnReal(int c) const { return sqlite3_column_double(stmt_, c); }
  // Text or blob bytes ("" for NULL).
  std::string ColumnText(int c) const {
    const void* p = sqlite3_column_blob(stmt_, c);
    const int n = sqlite3_column_bytes(stmt_, c);
    return p ? std::string(static_cast<const char*>(p), static_cast<std::size_t>(n)) : std::string();
  }

 private:
  Statement& Check(int rc, const char* what) {
    if (rc != SQLITE_OK) Failed(what);
    return *this;
  }
  [[noreturn]] void Failed(const char* what) {
    fail_(what);
    std::abort();  // `fail` must throw
  }

  sqlite3* db_ = nullptr;
  sqlite3_stmt* stmt_ = nullptr;
  Fail fail_;
  std::function<void()> release_;
};

}  // namespace fabatlas::sqlite
