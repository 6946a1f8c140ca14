// Writing the published artifact (artifact.h, docs/artifact.md): every
// table in primary-key order into a temporary file in one transaction, the
// manifest with the tables' checksums, then a flush and a rename into place.
#include <fcntl.h>
#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <nlohmann/json.hpp>
#include <type_traits>
#include <utility>

#include "artifact_file.h"
#include "fabatlas/artifact/artifact.h"
#include "fabatlas/error.h"
#include "fabatlas/exact_decimal.h"
#include "fabatlas/key_list_text.h"
#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sampling/design_space.h"
#include "fabatlas/sampling/point_key_text.h"
#include "fabatlas/sha256.h"

namespace fabatlas::artifact {

namespace fs = std::filesystem;

namespace {

using format::Corrupt;
using format::Db;
using format::ForEachManifestField;
using format::kChecksumPrefix;
using format::kFailureSharePrefix;
using format::kPageSize;
using format::kSchema;
using format::kTables;
using format::SamplesTableSql;
using format::Stmt;
using format::StopName;
using format::TableChecksum;

void FsyncPath(const fs::path& path, bool directory) {
  int fd = ::open(path.c_str(), (directory ? O_RDONLY | O_DIRECTORY : O_RDONLY) | O_CLOEXEC);
  if (fd < 0) throw ResourceError(path.string() + ": cannot open to flush: " + std::strerror(errno));
  int rc = ::fsync(fd);
  int err = errno;
  ::close(fd);
  if (rc != 0) throw ResourceError(path.string() + ": cannot flush to disk: " + std::strerror(err));
}

void InsertManifest(Db& db, const std::map<std::string, std::string>& rows) {
  Stmt s(db, "INSERT INTO manifest (key, value) VALUES (?, ?)");
  for (const auto& [key, value] : rows) {
    s.BindText(1, key).BindText(2, value);
    s.Run();
  }
}

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

// The form's dimensions (their enumerated values as JSON).
void InsertDimensions(Db& db, const Artifact& a) {
  const sampling::Form& form = a.form;
  const int n = static_cast<int>(form.dimensions.size());
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

// The k-d trees and their nodes.
void InsertTrees(Db& db, const Artifact& a) {
  const sampling::Form& form = a.form;
  Stmt t(db, "INSERT INTO trees VALUES (?, ?)");
  Stmt s(db, "INSERT INTO nodes VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  for (std::size_t ti = 0; ti < form.trees.size(); ++ti) {
    const auto& tree = form.trees[ti];
    t.Bind(1, static_cast<std::int64_t>(ti)).BindText(2, sampling::PointKeyText({tree.cell.begin(), tree.cell.end()}));
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

// The samples table (one u column per dimension, SamplesTableSql) and every sample with its properties.
void InsertSamples(Db& db, const Artifact& a) {
  const sampling::Form& form = a.form;
  const int n = static_cast<int>(form.dimensions.size());
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

// ΔG between pairs of samples.
void InsertGeometryChanges(Db& db, const Artifact& a) {
  const sampling::Form& form = a.form;
  Stmt s(db, "INSERT INTO geometry_changes VALUES (?, ?, ?)");
  for (const auto& [edge, dg] : form.geometry_changes) {
    s.Bind(1, edge.first).Bind(2, edge.second).BindReal(3, dg);
    s.Run();
  }
}

// The geometry cache's entries in key order, each with its geometry (taken on demand through
// Artifact::cache_geometry, one at a time); counted in `summary`.
void InsertCacheEntries(Db& db, const Artifact& a, ArtifactWriteSummary& summary) {
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

// The cache curves in (strategy, step) order.
void InsertCacheCurves(Db& db, const Artifact& a) {
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

// The starting points (each names an existing sample).
void InsertStartingPoints(Db& db, const Artifact& a) {
  const sampling::Form& form = a.form;
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

// The job bundle: the design file, the files it names, the job file.
void InsertBundleFiles(Db& db, const Artifact& a) {
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

void InsertContent(Db& db, const Artifact& a, ArtifactWriteSummary& summary) {
  const int n = static_cast<int>(a.form.dimensions.size());
  // A form of no dimensions is one sample: a model with nothing exposed.
  if (n < 0 || n > sampling::kMaxDimensions)
    throw InputError("artifact: a form needs 0 to " + std::to_string(sampling::kMaxDimensions) +
                     " dimensions, this one has " + std::to_string(n));
  InsertDimensions(db, a);
  InsertTrees(db, a);
  InsertSamples(db, a);
  InsertGeometryChanges(db, a);
  InsertCacheEntries(db, a, summary);
  InsertCacheCurves(db, a);
  InsertStartingPoints(db, a);
  InsertBundleFiles(db, a);
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

}  // namespace fabatlas::artifact
