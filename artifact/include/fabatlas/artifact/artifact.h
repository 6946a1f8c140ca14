// fabatlas/artifact/artifact.h — the published artifact of a job: one SQLite
// database file, `<design>.fabatlas` (schema and the
// meaning of every column in docs/artifact.md).
//
// What it holds: a manifest (schema version, design hash, code version,
// sampling parameters, Fab Forms Table 3 statistics, a SHA-256 checksum of
// every table's canonical content), the sampled form (dimensions, the k-d tree
// of every bootstrap cell, every sample with validity, failure type and
// properties, every ΔG), the chosen geometry cache (subtrees as exact level
// sets and as glTF binary meshes), the cache curves of Fab Forms Fig. 13, the
// customisation starting points (Fab Forms Sec. 7.4) and the job bundle (job
// file, design file and the files it names) so a consumer can re-evaluate
// previews.
//
// Determinism: the file is a pure function of the Artifact value. No
// timestamps, rows inserted in key order, fixed page size, written straight
// into the file in one transaction (no journal); equal content gives
// byte-identical files. Measured times
// (evaluator CPU seconds, measured subtree times) are *not* part of it: they
// differ between runs and would break byte-identity across worker counts;
// the job's statistics.json beside the artifact keeps them.
//
// Atomicity: WriteArtifact writes `<path>.tmp-<pid>`, fsyncs it, renames it
// onto `path` and fsyncs the directory, so a crash never leaves a partial
// file under the final name.
//
// Versions: the schema version is stored as SQLite's user_version and in the
// manifest. Readers accept every version up to kArtifactSchemaVersion
// (older versions are converted on read, see docs/artifact.md).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "fabatlas/sampling/form.h"

namespace fabatlas::artifact {

// The schema version WriteArtifact writes.
inline constexpr int kArtifactSchemaVersion = 2;
// SQLite application_id of artifact files ("FbAt").
inline constexpr std::int32_t kArtifactApplicationId = 0x46624174;

// Fab Forms Table 3, the deterministic part (no CPU time, see above).
struct ArtifactStatistics {
  std::int64_t samples = 0;
  std::int64_t valid_samples = 0;
  std::int64_t leaves = 0;
  std::int64_t geometry_changes = 0;  // ΔG values stored
  double valid_volume_percent = 0.0;  // all-valid leaf volume / bounded volume, %
  // Failure type -> share of invalid samples (sums to 1 when any invalid).
  std::map<std::string, double> failure_shares;
};

// The geometry cache as chosen by the cache task (Fab Forms Sec. 6, Fig. 14).
// Sizes are in entries and bytes of level-set memory (SubtreeRecord::bytes).
struct CacheSummary {
  std::string strategy;                         // "naive", "opt_ave", "opt_max" (cache::StrategyName); empty = no cache
  std::int64_t budget_bytes = 0;                // memory budget from the job file (0 = none)
  double threshold_seconds = 0.0;               // subtrees whose root took less were not stored
  std::string cost_model;                       // how entry costs were obtained (docs/cache.md)
  std::int64_t top_entries = 0, top_bytes = 0;  // H_TOP: root geometry of every valid sample
  std::int64_t opt_entries = 0, opt_bytes = 0;  // H_opt: the chosen cache
  std::int64_t rfree_entries = 0, rfree_bytes = 0;  // H_rfree: every non-redundant subtree
};

struct Manifest {
  // Version of the file read (WriteArtifact always writes kArtifactSchemaVersion).
  int schema_version = kArtifactSchemaVersion;
  std::string design_name;
  // SHA-256 hex of what evaluation depends on (protocol::EvaluationDigest:
  // the design file and the files it names).
  std::string design_hash;
  std::string code_version;  // protocol::kCodeVersion of the producer
  // Sampling parameters (docs/job-format.md); the dimensions are in the form.
  int subdivisions = 5;
  int max_depth = 0;
  double dg_threshold = 0.0;
  std::int64_t max_samples = 0;
  ArtifactStatistics statistics;
  CacheSummary cache;
  // Table name -> SHA-256 hex of its canonical content (docs/artifact.md).
  // Filled in by WriteArtifact (input ignored) and verified by ReadArtifact.
  std::map<std::string, std::string> checksums;
};

// One subtree of the geometry cache, keyed by (τ, ρ) (design::SubtreeRecord).
struct CacheEntry {
  std::string key;                    // hex SHA-256 of (τ, ρ, voxel size)
  std::string op;                     // the subtree root's operation, e.g. "union"
  std::vector<std::string> children;  // keys of the child subtrees
  std::int64_t bytes = 0;             // level-set memory of the geometry
  // Cost of computing the root from its children, in seconds, as used by the
  // optimiser; deterministic (the cost model of docs/cache.md), not a
  // measurement of this run.
  double cost_seconds = 0.0;
  bool in_opt = true;       // member of the chosen cache H_opt (loaded by previews)
  bool in_rfree = true;     // member of H_rfree (for measuring t_rfree, Fig. 14)
  std::string grid;         // geometry::Solid::Serialize() bytes (exact level set)
  std::string glb;          // the zero iso-surface as glTF 2.0 binary (mm, +Y up untouched)
  std::string grid_sha256;  // SHA-256 hex of `grid`; filled in by WriteArtifact
};

// One point of a Fig. 13 curve: predicted preview time over all samples with
// the first `entries` subtrees chosen by `strategy`.
struct CacheCurvePoint {
  std::string strategy;   // "naive", "opt_ave", "opt_max"
  std::int64_t step = 0;  // position along the curve, from 0 (no cache)
  std::int64_t entries = 0;
  std::int64_t bytes = 0;
  double mean_seconds = 0.0;   // E_H[preview time], Fab Forms Eq. 3
  double worst_seconds = 0.0;  // max_u T_H(u)
};

// A customisation starting point (Fab Forms Sec. 7.4).
struct StartingPoint {
  std::int64_t sample_id = 0;  // index into form.samples (a valid sample)
  int component = 0;           // connected component of the valid-sample graph
  std::vector<double> u;       // the sample's coordinates (filled in by ReadArtifact)
};

// The job's inputs (fabatlas.v1.JobBundle as plain data).
struct JobBundle {
  std::string job_file_name, job_file;        // name and bytes
  std::string design_file_name, design_file;  // name and bytes
  std::map<std::string, std::string> files;   // path relative to the design -> bytes
};

struct Artifact {
  Manifest manifest;
  sampling::Form form;                         // dimensions, k-d trees, samples, ΔG values
  std::vector<CacheEntry> cache;               // sorted by key on write
  std::vector<CacheCurvePoint> cache_curves;   // sorted by (strategy, step) on write
  std::vector<StartingPoint> starting_points;  // in the given order
  JobBundle bundle;
  // Optional, for caches too large to hold in memory: WriteArtifact calls it
  // for every entry of `cache` whose grid is empty, just before writing its
  // row, to fill in grid and glb; the geometry is dropped once the row is
  // written, so the writer holds one entry's geometry at a time. Returning
  // false leaves the entry out of the file (ArtifactWriteSummary counts it).
  std::function<bool(CacheEntry& entry)> cache_geometry;
};

struct ArtifactWriteSummary {
  std::int64_t cache_entries = 0;           // cache entry rows written
  std::int64_t cache_entries_left_out = 0;  // cache_geometry returned false
};

struct ArtifactReadOptions {
  // Load cache entries' grid and glb bytes (false: metadata only, fast; the
  // memory then does not grow with the cache: read geometry with
  // ReadCacheGeometry).
  bool load_geometry = true;
  // Recompute and compare every checksum of the manifest.
  bool verify_checksums = true;
};

// Reads an artifact of any schema version up to kArtifactSchemaVersion.
// Throws InputError with one line "<path>: <what is wrong>" for a missing or
// unreadable file, a file that is not an SQLite database or not an artifact,
// a truncated file, a newer schema version, a missing table or column, a
// checksum mismatch or inconsistent content.
Artifact ReadArtifact(const std::filesystem::path& path, const ArtifactReadOptions& options = {});

// Reads the geometry (grid and glb) of the cache entries `want` accepts,
// one row at a time in key order: `want` sees an entry's metadata (no
// geometry), `visit` gets the entry with its geometry, checked against its
// grid_sha256, and the bytes are dropped when it returns. Memory: one
// entry's geometry at a time, whatever the artifact's size. Tables are not
// checksummed here (ReadArtifact does that). Throws InputError like
// ReadArtifact.
void ReadCacheGeometry(const std::filesystem::path& path, const std::function<bool(const CacheEntry&)>& want,
                       const std::function<void(CacheEntry& entry)>& visit);

// Writes the artifact atomically (see above). Throws InputError naming the
// path for an inconsistent Artifact (e.g. a starting point that names no
// sample) and ResourceError on I/O failure (a full disk).
ArtifactWriteSummary WriteArtifact(const Artifact& artifact, const std::filesystem::path& path);

// The manifest's statistics computed from a form (valid volume %, failure
// shares, counts), as sampling::SampleDesignSpace reports them.
ArtifactStatistics StatisticsOf(const sampling::Form& form);

}  // namespace fabatlas::artifact
