// Internal: the artifact's SQLite file as the writer (write_artifact.cc)
// and the reader (read_artifact.cc) both see it: its schema, the tables a
// checksum covers, the SQLite connection and statements whose errors are
// Corrupt, the text encodings of its columns and the manifest's fields
// (docs/artifact.md).
#pragma once

#include <sqlite3.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "fabatlas/artifact/artifact.h"
#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sqlite/connection.h"

namespace fabatlas::artifact::format {

inline constexpr int kPageSize = 4096;

// ---- schema ----------------------------------------------------------------------
//
// Version 2 (written): `samples` has one column u<d> per dimension of the
// form (SamplesTableSql). Version 1 (read only): u0..u5 whatever the
// dimension count, NULL beyond it; everything else is the same.

inline constexpr const char* kSchema = R"sql(
CREATE TABLE manifest (key TEXT PRIMARY KEY, value TEXT NOT NULL) WITHOUT ROWID;
CREATE TABLE dimensions (idx INTEGER PRIMARY KEY, name TEXT NOT NULL, kind TEXT NOT NULL,
  lo REAL NOT NULL, hi REAL NOT NULL, enum_values TEXT NOT NULL);
CREATE TABLE trees (tree INTEGER PRIMARY KEY, cell TEXT NOT NULL);
CREATE TABLE nodes (tree INTEGER NOT NULL, node INTEGER NOT NULL, depth INTEGER NOT NULL,
  lo TEXT NOT NULL, hi TEXT NOT NULL, split_dimension INTEGER NOT NULL, split_key INTEGER NOT NULL,
  child_lo INTEGER NOT NULL, child_hi INTEGER NOT NULL, stop TEXT NOT NULL,
  PRIMARY KEY (tree, node)) WITHOUT ROWID;
CREATE TABLE sample_properties (sample_id INTEGER NOT NULL, name TEXT NOT NULL, value REAL NOT NULL,
  PRIMARY KEY (sample_id, name)) WITHOUT ROWID;
CREATE TABLE geometry_changes (a INTEGER NOT NULL, b INTEGER NOT NULL, dg REAL NOT NULL,
  PRIMARY KEY (a, b)) WITHOUT ROWID;
CREATE TABLE cache_entries (key TEXT PRIMARY KEY, op TEXT NOT NULL, children TEXT NOT NULL,
  bytes INTEGER NOT NULL, cost_seconds REAL NOT NULL, in_opt INTEGER NOT NULL, in_rfree INTEGER NOT NULL,
  grid BLOB NOT NULL, grid_sha256 TEXT NOT NULL, glb BLOB NOT NULL) WITHOUT ROWID;
CREATE TABLE cache_curves (strategy TEXT NOT NULL, step INTEGER NOT NULL, entries INTEGER NOT NULL,
  bytes INTEGER NOT NULL, mean_seconds REAL NOT NULL, worst_seconds REAL NOT NULL,
  PRIMARY KEY (strategy, step)) WITHOUT ROWID;
CREATE TABLE starting_points (idx INTEGER PRIMARY KEY, sample_id INTEGER NOT NULL, component INTEGER NOT NULL);
CREATE TABLE bundle_files (role TEXT NOT NULL, name TEXT NOT NULL, bytes BLOB NOT NULL,
  PRIMARY KEY (role, name)) WITHOUT ROWID;
)sql";

// The samples table of a form with `dimensions` dimensions (schema v2).
std::string SamplesTableSql(int dimensions);

// Tables covered by a checksum, with their canonical (primary key) order.
struct TableOrder {
  const char* table;
  const char* order;
};
inline constexpr TableOrder kTables[] = {
    {"dimensions", "idx"},
    {"trees", "tree"},
    {"nodes", "tree, node"},
    {"samples", "id"},
    {"sample_properties", "sample_id, name"},
    {"geometry_changes", "a, b"},
    {"cache_entries", "key"},
    {"cache_curves", "strategy, step"},
    {"starting_points", "idx"},
    {"bundle_files", "role, name"},
};

// ---- SQLite plumbing ----------------------------------------------------------

// Errors inside the reader carry only "what is wrong"; ReadArtifact prefixes the path.
struct Corrupt : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The artifact file's SQLite connection; its errors are Corrupt.
class Db : public sqlite::Connection {
 public:
  Db(const std::string& uri, int flags)
      : Connection(uri, flags, [](const std::string& message) { throw Corrupt(message); }) {
    sqlite3_extended_result_codes(get(), 1);
  }
};

// A prepared statement of the artifact file; SQLite errors are Corrupt.
class Stmt : public sqlite::Statement {
 public:
  Stmt(Db& db, const std::string& sql) : Statement(db.get(), sql, [&db](const std::string& what) { db.Fail(what); }) {}
};

// SHA-256 of a table's rows in primary-key order (docs/artifact.md), read
// and hashed row by row.
std::string TableChecksum(Db& db, const TableOrder& t);

// ---- text encodings -------------------------------------------------------------

// A point key's or box's integers from their text; Corrupt naming `what`
// when malformed.
std::vector<std::int64_t> SplitInts(const std::string& text, const char* what);

// A leaf's stop as its column text, and back (Corrupt when unknown).
const char* StopName(sampling::LeafStop s);
sampling::LeafStop StopOf(const std::string& s);

// ---- the manifest ---------------------------------------------------------------

// The manifest's fields under their keys (docs/artifact.md "manifest"), the
// one list the writer and the reader go through: visit(key, field) for each,
// in this order, with `m` a Manifest or a const Manifest. The failure shares
// and the checksums, keyed by prefix, are left to the callers.
template <typename M, typename Visit>
void ForEachManifestField(M& m, Visit&& visit) {
  visit("design_name", m.design_name);
  visit("design_hash", m.design_hash);
  visit("code_version", m.code_version);
  visit("sampling.subdivisions", m.subdivisions);
  visit("sampling.max_depth", m.max_depth);
  visit("sampling.dg_threshold", m.dg_threshold);
  visit("sampling.max_samples", m.max_samples);
  visit("statistics.samples", m.statistics.samples);
  visit("statistics.valid_samples", m.statistics.valid_samples);
  visit("statistics.leaves", m.statistics.leaves);
  visit("statistics.geometry_changes", m.statistics.geometry_changes);
  visit("statistics.valid_volume_percent", m.statistics.valid_volume_percent);
  visit("cache.strategy", m.cache.strategy);
  visit("cache.budget_bytes", m.cache.budget_bytes);
  visit("cache.threshold_seconds", m.cache.threshold_seconds);
  visit("cache.cost_model", m.cache.cost_model);
  visit("cache.top_entries", m.cache.top_entries);
  visit("cache.top_bytes", m.cache.top_bytes);
  visit("cache.opt_entries", m.cache.opt_entries);
  visit("cache.opt_bytes", m.cache.opt_bytes);
  visit("cache.rfree_entries", m.cache.rfree_entries);
  visit("cache.rfree_bytes", m.cache.rfree_bytes);
}

inline const char* const kFailureSharePrefix = "statistics.failure_share.";
inline const char* const kChecksumPrefix = "checksum.";

}  // namespace fabatlas::artifact::format
