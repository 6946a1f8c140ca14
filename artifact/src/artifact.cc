// The published artifact as one SQLite file (see artifact.h and
// docs/artifact.md for the schema).
#include "fabatlas/artifact/artifact.h"

#include <fcntl.h>
#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <type_traits>
#include <utility>

#include "fabatlas/error.h"
#include "fabatlas/exact_decimal.h"
#include "fabatlas/key_list_text.h"
#include "fabatlas/sha256.h"
#include "fabatlas/sampling/design_space.h"
#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sampling/point_key_text.h"
#include "fabatlas/sqlite/connection.h"

namespace fabatlas::artifact {

namespace fs = std::filesystem;

namespace {

constexpr int kPageSize = 4096;

// ---- schema ----------------------------------------------------------------------
//
// Version 2 (written): `samples` has one column u<d> per dimension of the
// form (SamplesTableSql). Version 1 (read only): u0..u5 whatever the
// dimension count, NULL beyond it; everything else is the same.

constexpr const char* kSchema = R"sql(
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
std::string SamplesTableSql(int dimensions) {
  std::string sql = "CREATE TABLE samples (id INTEGER PRIMARY KEY, key TEXT NOT NULL UNIQUE";
  for (int d = 0; d < dimensions; ++d) sql += ", u" + std::to_string(d) + " REAL NOT NULL";
  return sql + ", valid INTEGER NOT NULL, failure TEXT NOT NULL);";
}

// Tables covered by a checksum, with their canonical (primary key) order.
struct TableOrder {
  const char* table;
  const char* order;
};
constexpr TableOrder kTables[] = {
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

// SHA-256 fed in pieces (the canonical content of a table with cache
// entries is as large as the artifact; only ~1 MiB of it is held at a time).
class Sha256Stream {
 public:
  std::string& buffer() { return buffer_; }
  // Hashes the buffer when it holds at least `min_bytes`.
  void Flush(std::size_t min_bytes = 1 << 20) {
    if (buffer_.size() < min_bytes) return;
    sha_.Update(buffer_);
    buffer_.clear();
  }
  std::string Hex() {
    Flush(0);
    return sha_.Hex();
  }

 private:
  Sha256 sha_;
  std::string buffer_;
};

// SHA-256 of a table's rows in primary-key order (docs/artifact.md), read
// and hashed row by row.
std::string TableChecksum(Db& db, const TableOrder& t) {
  Stmt s(db, std::string("SELECT * FROM ") + t.table + " ORDER BY " + t.order);
  Sha256Stream sha;
  std::string& canonical = sha.buffer();
  auto put64 = [&](std::uint64_t v) {
    for (int i = 0; i < 8; ++i) canonical.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
  };
  while (s.Next()) {
    for (int c = 0; c < s.ColumnCount(); ++c) {
      switch (s.ColumnType(c)) {
        case SQLITE_NULL:
          canonical.push_back('N');
          break;
        case SQLITE_INTEGER:
          canonical.push_back('I');
          put64(static_cast<std::uint64_t>(s.ColumnInt(c)));
          break;
        case SQLITE_FLOAT: {
          canonical.push_back('R');
          double d = s.ColumnReal(c);
          std::uint64_t bits;
          std::memcpy(&bits, &d, 8);
          put64(bits);
          break;
        }
        default: {
          canonical.push_back(s.ColumnType(c) == SQLITE_TEXT ? 'T' : 'B');
          std::string v = s.ColumnText(c);
          put64(v.size());
          canonical += v;
        }
      }
    }
    sha.Flush();
  }
  return sha.Hex();
}

// ---- text encodings -------------------------------------------------------------

std::vector<std::int64_t> SplitInts(const std::string& text, const char* what) {
  auto ints = sampling::ParsePointKeyText(text);
  if (!ints) throw Corrupt(std::string("malformed ") + what + " '" + text + "'");
  return *ints;
}

const char* StopName(sampling::LeafStop s) {
  switch (s) {
    case sampling::LeafStop::kNone:
      return "none";
    case sampling::LeafStop::kThreshold:
      return "threshold";
    case sampling::LeafStop::kMaxDepth:
      return "max_depth";
    case sampling::LeafStop::kUnsplittable:
      return "unsplittable";
    case sampling::LeafStop::kBudget:
      return "budget";
  }
  return "none";
}

sampling::LeafStop StopOf(const std::string& s) {
  for (auto v : {sampling::LeafStop::kNone, sampling::LeafStop::kThreshold, sampling::LeafStop::kMaxDepth,
                 sampling::LeafStop::kUnsplittable, sampling::LeafStop::kBudget})
    if (s == StopName(v)) return v;
  throw Corrupt("unknown leaf stop '" + s + "'");
}

// ---- file plumbing ------------------------------------------------------------------

void FsyncPath(const fs::path& path, bool directory) {
  int fd = ::open(path.c_str(), (directory ? O_RDONLY | O_DIRECTORY : O_RDONLY) | O_CLOEXEC);
  if (fd < 0) throw ResourceError(path.string() + ": cannot open to flush: " + std::strerror(errno));
  int rc = ::fsync(fd);
  int err = errno;
  ::close(fd);
  if (rc != 0) throw ResourceError(path.string() + ": cannot flush to disk: " + std::strerror(err));
}

std::uint32_t BigEndian(const unsigned char* p, int n) {
  std::uint32_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}

// Checks SQLite's 100-byte header: magic, application id, schema version,
// and that the file holds every page the header announces. Returns the
// schema version.
int CheckHeader(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Corrupt("no such file");
  if (!fs::is_regular_file(path, ec)) throw Corrupt("not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Corrupt("cannot read");
  unsigned char h[100] = {};
  in.read(reinterpret_cast<char*>(h), sizeof h);
  const auto got = in.gcount();
  if (got < 16 || std::memcmp(h, "SQLite format 3", 16) != 0)
    throw Corrupt("not a fabatlas artifact (not an SQLite database)");
  if (got < 100) throw Corrupt("truncated (" + std::to_string(got) + " bytes, shorter than the SQLite header)");
  if (static_cast<std::int32_t>(BigEndian(h + 68, 4)) != kArtifactApplicationId)
    throw Corrupt("not a fabatlas artifact (an SQLite database with application id " +
                  std::to_string(static_cast<std::int32_t>(BigEndian(h + 68, 4))) + ")");
  std::uint32_t page_size = BigEndian(h + 16, 2);
  if (page_size == 1) page_size = 65536;
  const std::uint32_t pages = BigEndian(h + 28, 4);
  const bool size_valid = pages != 0 && BigEndian(h + 24, 4) == BigEndian(h + 92, 4);
  const auto file_size = fs::file_size(path, ec);
  if (size_valid && file_size < std::uint64_t{page_size} * pages)
    throw Corrupt("truncated (" + std::to_string(file_size) + " of " +
                  std::to_string(std::uint64_t{page_size} * pages) + " bytes)");
  const int version = static_cast<int>(BigEndian(h + 60, 4));
  if (version < 1) throw Corrupt("not a fabatlas artifact (schema version 0)");
  if (version > kArtifactSchemaVersion)
    throw Corrupt("written by a newer fabatlas (schema version " + std::to_string(version) +
                  "; this reader knows versions 1 to " + std::to_string(kArtifactSchemaVersion) + ")");
  return version;
}

// ---- writing ----------------------------------------------------------------------------

void InsertManifest(Db& db, const std::map<std::string, std::string>& rows) {
  Stmt s(db, "INSERT INTO manifest (key, value) VALUES (?, ?)");
  for (const auto& [key, value] : rows) {
    s.BindText(1, key).BindText(2, value);
    s.Run();
  }
}

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

const char* const kFailureSharePrefix = "statistics.failure_share.";
const char* const kChecksumPrefix = "checksum.";

std::map<std::string, std::string> ManifestRows(const Artifact& a) {
  Manifest m = a.manifest;
  m.subdivisions = a.form.subdivisions;  // the form's is the one that holds
  std::map<std::string, std::string> r;
  r["format"] = "fabatlas.artifact";
  r["schema_version"] = std::to_string(kArtifactSchemaVersion);
  ForEachManifestField(std::as_const(m), [&r](const char* key, const auto& field) {
    using T = std::decay_t<decltype(field)>;
    if constexpr (std::is_same_v<T, std::string>)
      r[key] = field;
    else if constexpr (std::is_same_v<T, double>)
      r[key] = ExactDecimal(field);
    else
      r[key] = std::to_string(field);
  });
  for (const auto& [type, share] : m.statistics.failure_shares) r[kFailureSharePrefix + type] = ExactDecimal(share);
  return r;
}

void InsertContent(Db& db, const Artifact& a, ArtifactWriteSummary& summary) {
  const sampling::Form& form = a.form;
  const int n = static_cast<int>(form.dimensions.size());
  if (n < 1 || n > sampling::kMaxDimensions)
    throw InputError("artifact: a form needs 1 to " + std::to_string(sampling::kMaxDimensions) +
                     " dimensions, this one has " + std::to_string(n));
  {
    Stmt s(db, "INSERT INTO dimensions VALUES (?, ?, ?, ?, ?, ?)");
    for (int d = 0; d < n; ++d) {
      const auto& dim = form.dimensions[d];
      s.Bind(1, d)
          .BindText(2, dim.name)
          .BindText(3, sampling::DimensionKindName(dim.kind))
          .BindReal(4, dim.lo)
          .BindReal(5, dim.hi);
      s.BindText(6, dim.kind == sampling::DimensionKind::kEnumerated ? nlohmann::json(dim.values).dump() : "");
      s.Run();
    }
  }
  {
    Stmt t(db, "INSERT INTO trees VALUES (?, ?)");
    Stmt s(db, "INSERT INTO nodes VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    for (std::size_t ti = 0; ti < form.trees.size(); ++ti) {
      const auto& tree = form.trees[ti];
      t.Bind(1, static_cast<std::int64_t>(ti))
          .BindText(2, sampling::PointKeyText({tree.cell.begin(), tree.cell.end()}));
      t.Run();
      for (std::size_t ni = 0; ni < tree.nodes.size(); ++ni) {
        const auto& node = tree.nodes[ni];
        s.Bind(1, static_cast<std::int64_t>(ti)).Bind(2, static_cast<std::int64_t>(ni)).Bind(3, node.depth);
        s.BindText(4, sampling::PointKeyText(node.lo))
            .BindText(5, sampling::PointKeyText(node.hi))
            .Bind(6, node.split_dimension);
        s.Bind(7, node.split_key).Bind(8, node.children[0]).Bind(9, node.children[1]).BindText(10, StopName(node.stop));
        s.Run();
      }
    }
  }
  {
    db.Exec(SamplesTableSql(n));
    std::string insert = "INSERT INTO samples VALUES (?, ?";
    for (int d = 0; d < n; ++d) insert += ", ?";
    Stmt s(db, insert + ", ?, ?)");
    Stmt p(db, "INSERT INTO sample_properties VALUES (?, ?, ?)");
    for (std::size_t i = 0; i < form.samples.size(); ++i) {
      const auto& sample = form.samples[i];
      if (static_cast<int>(sample.u.size()) != n || static_cast<int>(sample.key.size()) != n)
        throw InputError("artifact: sample " + std::to_string(i) + " has the wrong dimension");
      s.Bind(1, static_cast<std::int64_t>(i)).BindText(2, sampling::PointKeyText(sample.key));
      for (int d = 0; d < n; ++d) s.BindReal(3 + d, sample.u[d]);
      s.Bind(3 + n, sample.outcome.valid ? 1 : 0).BindText(4 + n, sample.outcome.failure_type);
      s.Run();
      for (const auto& [name, value] : sample.outcome.properties) {
        p.Bind(1, static_cast<std::int64_t>(i)).BindText(2, name).BindReal(3, value);
        p.Run();
      }
    }
  }
  {
    Stmt s(db, "INSERT INTO geometry_changes VALUES (?, ?, ?)");
    for (const auto& [edge, dg] : form.geometry_changes) {
      s.Bind(1, edge.first).Bind(2, edge.second).BindReal(3, dg);
      s.Run();
    }
  }
  {
    std::vector<const CacheEntry*> entries;
    for (const auto& e : a.cache) entries.push_back(&e);
    std::sort(entries.begin(), entries.end(), [](auto* x, auto* y) { return x->key < y->key; });
    Stmt s(db, "INSERT INTO cache_entries VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    for (std::size_t i = 0; i < entries.size(); ++i) {
      if (i > 0 && entries[i - 1]->key == entries[i]->key)
        throw InputError("artifact: cache entry " + entries[i]->key + " appears twice");
      // Geometry on demand (Artifact::cache_geometry): held for this row only.
      CacheEntry streamed;
      if (entries[i]->grid.empty() && a.cache_geometry) {
        streamed = *entries[i];
        if (!a.cache_geometry(streamed)) {
          ++summary.cache_entries_left_out;
          continue;
        }
      }
      const CacheEntry& e = streamed.grid.empty() ? *entries[i] : streamed;
      ++summary.cache_entries;
      s.BindText(1, e.key)
          .BindText(2, e.op)
          .BindText(3, KeyListText(e.children))
          .Bind(4, e.bytes)
          .BindReal(5, e.cost_seconds);
      s.Bind(6, e.in_opt ? 1 : 0)
          .Bind(7, e.in_rfree ? 1 : 0)
          .Bind(8, e.grid)
          .BindText(9, Sha256Hex(e.grid))
          .Bind(10, e.glb);
      s.Run();
    }
  }
  {
    std::vector<const CacheCurvePoint*> points;
    for (const auto& p : a.cache_curves) points.push_back(&p);
    std::sort(points.begin(), points.end(),
              [](auto* x, auto* y) { return std::tie(x->strategy, x->step) < std::tie(y->strategy, y->step); });
    Stmt s(db, "INSERT INTO cache_curves VALUES (?, ?, ?, ?, ?, ?)");
    for (const auto* p : points) {
      s.BindText(1, p->strategy).Bind(2, p->step).Bind(3, p->entries).Bind(4, p->bytes).BindReal(5, p->mean_seconds);
      s.BindReal(6, p->worst_seconds);
      s.Run();
    }
  }
  {
    Stmt s(db, "INSERT INTO starting_points VALUES (?, ?, ?)");
    for (std::size_t i = 0; i < a.starting_points.size(); ++i) {
      const auto& sp = a.starting_points[i];
      if (sp.sample_id < 0 || sp.sample_id >= static_cast<std::int64_t>(form.samples.size()))
        throw InputError("artifact: starting point " + std::to_string(i) + " names sample " +
                         std::to_string(sp.sample_id) + ", which does not exist");
      s.Bind(1, static_cast<std::int64_t>(i)).Bind(2, sp.sample_id).Bind(3, sp.component);
      s.Run();
    }
  }
  {
    Stmt s(db, "INSERT INTO bundle_files VALUES (?, ?, ?)");
    s.BindText(1, "design").BindText(2, a.bundle.design_file_name).Bind(3, a.bundle.design_file);
    s.Run();
    for (const auto& [name, bytes] : a.bundle.files) {
      s.BindText(1, "file").BindText(2, name).Bind(3, bytes);
      s.Run();
    }
    s.BindText(1, "job").BindText(2, a.bundle.job_file_name).Bind(3, a.bundle.job_file);
    s.Run();
  }
}

// ---- reading ----------------------------------------------------------------------------

std::map<std::string, std::string> ReadManifestRows(Db& db) {
  std::map<std::string, std::string> rows;
  Stmt s(db, "SELECT key, value FROM manifest ORDER BY key");
  while (s.Next()) rows[s.ColumnText(0)] = s.ColumnText(1);
  return rows;
}

struct ManifestReader {
  const std::map<std::string, std::string>& rows;
  std::string Text(const std::string& key) const {
    auto it = rows.find(key);
    if (it == rows.end()) throw Corrupt("manifest has no '" + key + "'");
    return it->second;
  }
  std::int64_t Int(const std::string& key) const {
    std::string v = Text(key);
    try {
      std::size_t used = 0;
      std::int64_t x = std::stoll(v, &used);
      if (used == v.size()) return x;
    } catch (const std::exception&) {
    }
    throw Corrupt("manifest '" + key + "' is not an integer: '" + v + "'");
  }
  double Real(const std::string& key) const {
    std::string v = Text(key);
    try {
      std::size_t used = 0;
      double x = std::stod(v, &used);
      if (used == v.size()) return x;
    } catch (const std::exception&) {
    }
    throw Corrupt("manifest '" + key + "' is not a number: '" + v + "'");
  }
};

// The columns of a cache entry's metadata, in the order CacheEntryMetadata
// reads them.
const std::string kCacheEntryMetadataColumns = "key, op, children, bytes, cost_seconds, in_opt, in_rfree, grid_sha256";

// A cache entry's metadata from a row that starts with
// kCacheEntryMetadataColumns; its geometry is left empty.
CacheEntry CacheEntryMetadata(Stmt& s) {
  CacheEntry e;
  e.key = s.ColumnText(0);
  e.op = s.ColumnText(1);
  e.children = ParseKeyListText(s.ColumnText(2));
  e.bytes = s.ColumnInt(3);
  e.cost_seconds = s.ColumnReal(4);
  e.in_opt = s.ColumnInt(5) != 0;
  e.in_rfree = s.ColumnInt(6) != 0;
  e.grid_sha256 = s.ColumnText(7);
  return e;
}

// The manifest: format and schema version (against the file header's
// `version`), every field, failure shares and table checksums; with
// options.verify_checksums every table checked against its checksum.
Manifest ReadManifest(Db& db, int version, const ArtifactReadOptions& options) {
  const auto rows = ReadManifestRows(db);
  ManifestReader m{rows};
  if (m.Text("format") != "fabatlas.artifact") throw Corrupt("manifest format is '" + m.Text("format") + "'");
  if (m.Int("schema_version") != version)
    throw Corrupt("manifest schema_version " + m.Text("schema_version") + " disagrees with the file header (" +
                  std::to_string(version) + ")");
  Manifest man;
  man.schema_version = version;
  ForEachManifestField(man, [&m](const char* key, auto& field) {
    using T = std::decay_t<decltype(field)>;
    if constexpr (std::is_same_v<T, std::string>)
      field = m.Text(key);
    else if constexpr (std::is_same_v<T, double>)
      field = m.Real(key);
    else
      field = static_cast<T>(m.Int(key));
  });
  const std::string share_prefix = kFailureSharePrefix, checksum_prefix = kChecksumPrefix;
  for (const auto& [key, value] : rows) {
    if (key.rfind(share_prefix, 0) == 0) man.statistics.failure_shares[key.substr(share_prefix.size())] = m.Real(key);
    if (key.rfind(checksum_prefix, 0) == 0) man.checksums[key.substr(checksum_prefix.size())] = value;
  }

  if (options.verify_checksums) {
    for (const auto& t : kTables) {
      auto it = man.checksums.find(t.table);
      if (it == man.checksums.end()) throw Corrupt(std::string("manifest has no checksum of table ") + t.table);
      if (TableChecksum(db, t) != it->second)
        throw Corrupt(std::string("table ") + t.table +
                      " does not match its checksum (the file was altered or damaged)");
    }
  }
  return man;
}

// The form's dimensions, in index order.
void ReadDimensions(Db& db, sampling::Form& form) {
  Stmt s(db, "SELECT idx, name, kind, lo, hi, enum_values FROM dimensions ORDER BY idx");
  while (s.Next()) {
    if (s.ColumnInt(0) != static_cast<std::int64_t>(form.dimensions.size()))
      throw Corrupt("dimension indices are not 0..n-1");
    sampling::Dimension d;
    d.name = s.ColumnText(1);
    std::string kind = s.ColumnText(2);
    if (!sampling::DimensionKindFromName(kind, &d.kind))
      throw Corrupt("dimension '" + d.name + "' has unknown kind '" + kind + "'");
    d.lo = s.ColumnReal(3);
    d.hi = s.ColumnReal(4);
    if (d.kind == sampling::DimensionKind::kEnumerated) {
      try {
        d.values = nlohmann::json::parse(s.ColumnText(5)).get<std::vector<std::string>>();
      } catch (const std::exception&) {
        throw Corrupt("dimension '" + d.name + "' has malformed enum_values");
      }
    }
    form.dimensions.push_back(std::move(d));
  }
}

// The samples of a form of n dimensions, in id order.
void ReadSamples(Db& db, int n, sampling::Form& form) {
  // Both versions have u0..u<n-1>; version 1 has NULL columns beyond them.
  std::string select = "SELECT id, key";
  for (int d = 0; d < n; ++d) select += ", u" + std::to_string(d);
  Stmt s(db, select + ", valid, failure FROM samples ORDER BY id");
  while (s.Next()) {
    const auto id = static_cast<std::int64_t>(form.samples.size());
    if (s.ColumnInt(0) != id) throw Corrupt("sample ids are not 0..n-1");
    sampling::FormSample sample;
    sample.key = SplitInts(s.ColumnText(1), "sample key");
    if (static_cast<int>(sample.key.size()) != n)
      throw Corrupt("sample " + std::to_string(id) + " has a key of the wrong dimension");
    for (int d = 0; d < n; ++d) {
      if (s.ColumnType(2 + d) != SQLITE_FLOAT && s.ColumnType(2 + d) != SQLITE_INTEGER)
        throw Corrupt("sample " + std::to_string(id) + " has no u" + std::to_string(d));
      sample.u.push_back(s.ColumnReal(2 + d));
    }
    sample.outcome.valid = s.ColumnInt(2 + n) != 0;
    sample.outcome.failure_type = s.ColumnText(3 + n);
    if (!form.sample_ids.emplace(sample.key, id).second) throw Corrupt("two samples share key " + s.ColumnText(1));
    form.samples.push_back(std::move(sample));
  }
}

// Every sample's properties.
void ReadSampleProperties(Db& db, sampling::Form& form) {
  Stmt s(db, "SELECT sample_id, name, value FROM sample_properties ORDER BY sample_id, name");
  while (s.Next()) {
    auto id = s.ColumnInt(0);
    if (id < 0 || id >= static_cast<std::int64_t>(form.samples.size()))
      throw Corrupt("a property names sample " + std::to_string(id) + ", which does not exist");
    form.samples[id].outcome.properties[s.ColumnText(1)] = s.ColumnReal(2);
  }
}

// Every tree has nodes, a split node's children exist and a leaf's corners
// are samples.
void CheckTrees(const sampling::Form& form) {
  for (std::size_t ti = 0; ti < form.trees.size(); ++ti) {
    const auto& tree = form.trees[ti];
    if (tree.nodes.empty()) throw Corrupt("tree " + std::to_string(ti) + " has no nodes");
    for (const auto& node : tree.nodes) {
      if (node.split_dimension >= 0) {
        for (int c : node.children)
          if (c <= 0 || c >= static_cast<int>(tree.nodes.size()))
            throw Corrupt("a node of tree " + std::to_string(ti) + " has a child index out of range");
      } else {
        try {
          sampling::CornerSampleIds(form, node);
        } catch (const std::out_of_range&) {
          throw Corrupt("a leaf of tree " + std::to_string(ti) + " has a corner without a sample");
        }
      }
    }
  }
}

// The k-d trees and their nodes (boxes of n dimensions), then CheckTrees.
void ReadTrees(Db& db, int n, sampling::Form& form) {
  Stmt t(db, "SELECT tree, cell FROM trees ORDER BY tree");
  while (t.Next()) {
    if (t.ColumnInt(0) != static_cast<std::int64_t>(form.trees.size())) throw Corrupt("tree indices are not 0..n-1");
    sampling::FormTree tree;
    for (auto c : SplitInts(t.ColumnText(1), "tree cell")) tree.cell.push_back(static_cast<int>(c));
    form.trees.push_back(std::move(tree));
  }
  Stmt s(db,
         "SELECT tree, node, depth, lo, hi, split_dimension, split_key, child_lo, child_hi, stop FROM nodes "
         "ORDER BY tree, node");
  while (s.Next()) {
    auto ti = s.ColumnInt(0);
    if (ti < 0 || ti >= static_cast<std::int64_t>(form.trees.size()))
      throw Corrupt("a node names a tree that does not exist");
    auto& tree = form.trees[ti];
    if (s.ColumnInt(1) != static_cast<std::int64_t>(tree.nodes.size()))
      throw Corrupt("node indices of tree " + std::to_string(ti) + " are not 0..n-1");
    sampling::FormNode node;
    node.depth = static_cast<int>(s.ColumnInt(2));
    node.lo = SplitInts(s.ColumnText(3), "node box");
    node.hi = SplitInts(s.ColumnText(4), "node box");
    node.split_dimension = static_cast<int>(s.ColumnInt(5));
    node.split_key = s.ColumnInt(6);
    node.children[0] = static_cast<int>(s.ColumnInt(7));
    node.children[1] = static_cast<int>(s.ColumnInt(8));
    node.stop = StopOf(s.ColumnText(9));
    if (static_cast<int>(node.lo.size()) != n || static_cast<int>(node.hi.size()) != n)
      throw Corrupt("a node of tree " + std::to_string(ti) + " has a box of the wrong dimension");
    if (node.split_dimension >= n) throw Corrupt("a node splits a dimension that does not exist");
    tree.nodes.push_back(std::move(node));
  }
  CheckTrees(form);
}

// ΔG between pairs of samples.
void ReadGeometryChanges(Db& db, sampling::Form& form) {
  Stmt s(db, "SELECT a, b, dg FROM geometry_changes ORDER BY a, b");
  const auto count = static_cast<std::int64_t>(form.samples.size());
  while (s.Next()) {
    auto x = s.ColumnInt(0), y = s.ColumnInt(1);
    if (x < 0 || y < 0 || x >= count || y >= count) throw Corrupt("a ΔG value names a sample that does not exist");
    form.geometry_changes[{x, y}] = s.ColumnReal(2);
  }
}

// The geometry cache's entries (their grids and meshes with
// options.load_geometry, each grid checked against its SHA-256) and curves.
void ReadCache(Db& db, const ArtifactReadOptions& options, Artifact& a) {
  {
    Stmt s(db, "SELECT " + kCacheEntryMetadataColumns + (options.load_geometry ? ", grid, glb" : "") +
                   " FROM cache_entries ORDER BY key");
    while (s.Next()) {
      CacheEntry e = CacheEntryMetadata(s);
      if (options.load_geometry) {
        e.grid = s.ColumnText(8);
        e.glb = s.ColumnText(9);
        if (Sha256Hex(e.grid) != e.grid_sha256)
          throw Corrupt("cache entry " + e.key + " does not match its grid_sha256");
      }
      a.cache.push_back(std::move(e));
    }
  }
  Stmt s(
      db,
      "SELECT strategy, step, entries, bytes, mean_seconds, worst_seconds FROM cache_curves ORDER BY strategy, step");
  while (s.Next())
    a.cache_curves.push_back(
        {s.ColumnText(0), s.ColumnInt(1), s.ColumnInt(2), s.ColumnInt(3), s.ColumnReal(4), s.ColumnReal(5)});
}

// The starting points, with their samples' parameter values.
void ReadStartingPoints(Db& db, Artifact& a) {
  const sampling::Form& form = a.form;
  Stmt s(db, "SELECT idx, sample_id, component FROM starting_points ORDER BY idx");
  while (s.Next()) {
    StartingPoint p;
    p.sample_id = s.ColumnInt(1);
    p.component = static_cast<int>(s.ColumnInt(2));
    if (p.sample_id < 0 || p.sample_id >= static_cast<std::int64_t>(form.samples.size()))
      throw Corrupt("a starting point names sample " + std::to_string(p.sample_id) + ", which does not exist");
    p.u = form.samples[p.sample_id].u;
    a.starting_points.push_back(std::move(p));
  }
}

// The bundle: exactly one job file and one design file, and the files they
// name.
void ReadBundle(Db& db, JobBundle& bundle) {
  Stmt s(db, "SELECT role, name, bytes FROM bundle_files ORDER BY role, name");
  int jobs = 0, designs = 0;
  while (s.Next()) {
    std::string role = s.ColumnText(0);
    if (role == "job") {
      bundle.job_file_name = s.ColumnText(1);
      bundle.job_file = s.ColumnText(2);
      ++jobs;
    } else if (role == "design") {
      bundle.design_file_name = s.ColumnText(1);
      bundle.design_file = s.ColumnText(2);
      ++designs;
    } else if (role == "file") {
      bundle.files[s.ColumnText(1)] = s.ColumnText(2);
    } else {
      throw Corrupt("bundle file of unknown role '" + role + "'");
    }
  }
  if (jobs != 1 || designs != 1) throw Corrupt("the bundle needs exactly one job file and one design file");
}

Artifact Read(Db& db, int version, const ArtifactReadOptions& options) {
  Artifact a;
  a.manifest = ReadManifest(db, version, options);
  sampling::Form& form = a.form;
  form.subdivisions = a.manifest.subdivisions;
  ReadDimensions(db, form);
  const int n = static_cast<int>(form.dimensions.size());
  const int max_dimensions = version == 1 ? 6 : sampling::kMaxDimensions;
  if (n < 1 || n > max_dimensions)
    throw Corrupt("the form has " + std::to_string(n) + " dimensions (1 to " + std::to_string(max_dimensions) +
                  " expected)");
  ReadSamples(db, n, form);
  ReadSampleProperties(db, form);
  ReadTrees(db, n, form);
  ReadGeometryChanges(db, form);
  ReadCache(db, options, a);
  ReadStartingPoints(db, a);
  ReadBundle(db, a.bundle);
  try {
    form.space();
  } catch (const std::exception& e) {
    throw Corrupt(std::string("invalid dimensions: ") + e.what());
  }
  return a;
}

}  // namespace

ArtifactStatistics StatisticsOf(const sampling::Form& form) {
  ArtifactStatistics s;
  s.samples = static_cast<std::int64_t>(form.samples.size());
  s.geometry_changes = static_cast<std::int64_t>(form.geometry_changes.size());
  std::int64_t invalid = 0;
  for (const auto& sample : form.samples) {
    if (sample.outcome.valid) {
      ++s.valid_samples;
      continue;
    }
    ++invalid;
    s.failure_shares[sample.outcome.failure_type] += 1.0;
  }
  for (auto& [type, share] : s.failure_shares) share /= static_cast<double>(invalid);
  for (const auto& tree : form.trees)
    for (const auto& node : tree.nodes)
      if (node.split_dimension < 0) ++s.leaves;
  if (!form.trees.empty()) s.valid_volume_percent = sampling::ValidVolumePercent(form);
  return s;
}

ArtifactWriteSummary WriteArtifact(const Artifact& artifact, const fs::path& path) {
  fs::path tmp = path;
  tmp += ".tmp-" + std::to_string(::getpid());
  std::error_code ec;
  fs::remove(tmp, ec);
  ArtifactWriteSummary summary;
  try {
    {
      // Straight into the temporary file, one transaction, no journal (a
      // failed write only leaves the temporary file, which is removed), so
      // memory holds SQLite's page cache and one cache entry, not the file.
      Db db(tmp.string(), SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
      db.Exec("PRAGMA page_size = " + std::to_string(kPageSize) +
              "; PRAGMA journal_mode = OFF; PRAGMA synchronous = OFF; PRAGMA cache_size = -16384;"
              " PRAGMA application_id = " +
              std::to_string(kArtifactApplicationId) +
              "; PRAGMA user_version = " + std::to_string(kArtifactSchemaVersion) + "; PRAGMA encoding = 'UTF-8';");
      db.Exec("BEGIN");
      db.Exec(kSchema);
      InsertContent(db, artifact, summary);
      auto rows = ManifestRows(artifact);
      for (const auto& t : kTables) rows[kChecksumPrefix + std::string(t.table)] = TableChecksum(db, t);
      InsertManifest(db, rows);
      db.Exec("COMMIT");
    }
    FsyncPath(tmp, false);
  } catch (const Corrupt& e) {
    fs::remove(tmp, ec);
    std::string what = e.what();
    if (what.find("full") != std::string::npos)
      throw ResourceError(path.string() + ": disk full while writing the artifact");
    throw ResourceError(path.string() + ": cannot write the artifact: " + what);
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp);
    throw ResourceError(path.string() + ": cannot rename the artifact into place: " + ec.message());
  }
  fs::path dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  FsyncPath(dir, true);
  return summary;
}

namespace {

// The artifact opened read-only. immutable=1: published artifacts never
// change; no locks, no -wal/-shm files.
std::unique_ptr<Db> OpenArtifact(const fs::path& path) {
  char* uri = sqlite3_mprintf("file:%q?immutable=1", fs::absolute(path).string().c_str());
  std::string uri_text = uri ? uri : "";
  sqlite3_free(uri);
  return std::make_unique<Db>(uri_text, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI);
}

// Runs `read` on the artifact at `path`: what it finds wrong (Corrupt, or any
// exception but an InputError) becomes one InputError naming the file.
template <typename Read>
auto ReadingArtifact(const fs::path& path, Read&& read) -> decltype(read()) {
  try {
    return read();
  } catch (const Corrupt& e) {
    throw InputError(path.string() + ": " + e.what());
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path.string() + ": corrupt artifact: " + e.what());
  }
}

}  // namespace

void ReadCacheGeometry(const fs::path& path, const std::function<bool(const CacheEntry&)>& want,
                       const std::function<void(CacheEntry& entry)>& visit) {
  ReadingArtifact(path, [&] {
    CheckHeader(path);
    auto db = OpenArtifact(path);
    // Metadata of every row first (small), then each wanted row's geometry
    // by its key, so only one entry's bytes are ever in memory.
    std::vector<CacheEntry> entries;
    {
      Stmt s(*db, "SELECT " + kCacheEntryMetadataColumns + " FROM cache_entries ORDER BY key");
      while (s.Next()) {
        CacheEntry e = CacheEntryMetadata(s);
        if (want(e)) entries.push_back(std::move(e));
      }
    }
    Stmt g(*db, "SELECT grid, glb FROM cache_entries WHERE key = ?");
    for (auto& e : entries) {
      g.BindText(1, e.key);
      if (!g.Next()) throw Corrupt("cache entry " + e.key + " disappeared");
      e.grid = g.ColumnText(0);
      e.glb = g.ColumnText(1);
      g.Reset();
      if (Sha256Hex(e.grid) != e.grid_sha256) throw Corrupt("cache entry " + e.key + " does not match its grid_sha256");
      visit(e);
      e.grid.clear();
      e.grid.shrink_to_fit();
      e.glb.clear();
      e.glb.shrink_to_fit();
    }
  });
}

Artifact ReadArtifact(const fs::path& path, const ArtifactReadOptions& options) {
  return ReadingArtifact(path, [&] {
    const int version = CheckHeader(path);
    auto db = OpenArtifact(path);
    return Read(*db, version, options);
  });
}

}  // namespace fabatlas::artifact
