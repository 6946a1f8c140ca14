// fabatlas/sqlite/connection.h — one SQLite connection: opened on
// construction, closed on destruction, its statements prepared once and
// reused (Cached) or prepared for one use (Prepare). The one connection type
// of the job store (storage/) and the artifact file (artifact/); include it
// only from .cc files (it includes sqlite3.h).
//
// Errors: every failing SQLite call ends in `raise(message)`, which must
// throw the owner's error (the job store's ResourceError naming the store,
// the artifact's Corrupt). The message is "<opening>: <SQLite's message>"
// when the database cannot be opened, SQLite's message for Exec and
// ExecInt, and
// "<what>: <SQLite's message>" for a statement's failing call ("prepare",
// "bind", "step").
//
// Threading: one thread at a time (SQLite's serialized mode guards the
// handle, not the cache of prepared statements).
#pragma once

#include <sqlite3.h>

#include <cstdint>
#include <cstdlib>
#include <functional>
#include <map>
#include <string>
#include <utility>

#include "fabatlas/sqlite/statement.h"

namespace fabatlas::sqlite {

class Connection {
 public:
  using Raise = std::function<void(const std::string& message)>;

  // Opens `uri` (a path, or a file: URI with SQLITE_OPEN_URI) with
  // sqlite3_open_v2 `flags`.
  Connection(const std::string& uri, int flags, Raise raise, const std::string& opening = "cannot open")
      : raise_(std::move(raise)) {
    if (sqlite3_open_v2(uri.c_str(), &handle_, flags, nullptr) != SQLITE_OK) {
      const std::string message = handle_ ? sqlite3_errmsg(handle_) : "out of memory";
      sqlite3_close(handle_);
      handle_ = nullptr;
      Raised(opening + ": " + message);
    }
  }
  ~Connection() {
    for (auto& [sql, entry] : statements_) sqlite3_finalize(entry.first);
    sqlite3_close(handle_);
  }
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  sqlite3* get() const { return handle_; }

  // raise("<what>: <SQLite's last message>").
  [[noreturn]] void Fail(const std::string& what) const { Raised(what + ": " + sqlite3_errmsg(handle_)); }

  // Runs one or more statements, their rows skipped (sqlite3_exec).
  void Exec(const std::string& sql) { Executed(sql, nullptr, nullptr); }

  // The integer in the first column of the last row of `sql` (0 without
  // rows or for NULL), e.g. a PRAGMA or a COUNT; errors as Exec's.
  std::int64_t ExecInt(const std::string& sql) {
    std::int64_t value = 0;
    Executed(
        sql,
        [](void* out, int columns, char** text, char**) {
          if (columns > 0) *static_cast<std::int64_t*>(out) = text[0] ? std::strtoll(text[0], nullptr, 10) : 0;
          return 0;
        },
        &value);
    return value;
  }

  // `sql` prepared for this one use, finalised when the statement goes.
  Statement Prepare(const std::string& sql) {
    return Statement(handle_, sql, [this](const std::string& what) { Fail(what); });
  }

  // `sql` from the connection's cache of prepared statements (preparing
  // costs more than running most statements), prepared on first use; reset
  // and handed back when the statement goes. When the cached one is in use
  // further up the stack, a fresh one for this use.
  Statement Cached(const std::string& sql) {
    auto it = statements_.find(sql);
    if (it == statements_.end()) {
      sqlite3_stmt* stmt = nullptr;
      if (sqlite3_prepare_v2(handle_, sql.c_str(), -1, &stmt, nullptr) != SQLITE_OK) Fail("prepare");
      it = statements_.emplace(sql, std::make_pair(stmt, false)).first;
    }
    if (it->second.second) return Prepare(sql);
    bool* in_use = &it->second.second;
    *in_use = true;
    return Statement(
        handle_, sql, [this](const std::string& what) { Fail(what); }, it->second.first, [in_use] { *in_use = false; });
  }

 private:
  void Executed(const std::string& sql, int (*row)(void*, int, char**, char**), void* out) {
    char* message = nullptr;
    if (sqlite3_exec(handle_, sql.c_str(), row, out, &message) != SQLITE_OK) {
      std::string text = message ? message : sqlite3_errmsg(handle_);
      sqlite3_free(message);
      Raised(text);
    }
  }
  [[noreturn]] void Raised(const std::string& message) const {
    raise_(message);
    std::abort();  // `raise` must throw
  }

  sqlite3* handle_ = nullptr;
  Raise raise_;
  // Cached statements by SQL text; the flag marks one in use.
  std::map<std::string, std::pair<sqlite3_stmt*, bool>> statements_;
};

}  // namespace fabatlas::sqlite
