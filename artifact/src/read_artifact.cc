// Reading the published artifact (artifact.h, docs/artifact.md): the file
// header checked, then every table read back and checked against the
// others (and, when asked, against its checksum); any fault is one
// InputError naming the file.
#include <sqlite3.h>

#include <cstring>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <type_traits>
#include <utility>

#include "artifact_file.h"
#include "fabatlas/artifact/artifact.h"
#include "fabatlas/error.h"
#include "fabatlas/key_list_text.h"
#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sampling/design_space.h"
#include "fabatlas/sha256.h"

namespace fabatlas::artifact {

namespace fs = std::filesystem;

namespace {

using format::Corrupt;
using format::Db;
using format::ForEachManifestField;
using format::kChecksumPrefix;
using format::kFailureSharePrefix;
using format::kTables;
using format::SplitInts;
using format::Stmt;
using format::StopOf;
using format::TableChecksum;

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
  const int min_dimensions = version == 1 ? 1 : 0;
  const int max_dimensions = version == 1 ? 6 : sampling::kMaxDimensions;
  if (n < min_dimensions || n > max_dimensions)
    throw Corrupt("the form has " + std::to_string(n) + " dimensions (" + std::to_string(min_dimensions) + " to " +
                  std::to_string(max_dimensions) + " expected)");
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
