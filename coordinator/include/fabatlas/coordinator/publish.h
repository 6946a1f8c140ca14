// fabatlas/coordinator/publish.h — the published artifact of a finished job
// (docs/artifact.md): what the coordinator writes as
// OUT/<design>.fabatlas beside form.json when a job's sampling finishes.
//
// The artifact is a pure function of the job bundle, the sampled form and the
// subtrees the samples evaluated (costed by a deterministic model), never of
// measured times, worker count or faults, so the same job always publishes
// the same bytes.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "fabatlas/cache/optimize_cache.h"
#include "fabatlas/cache/starting_points.h"
#include "fabatlas/design/design.h"

#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sampling/job_file.h"
#include "fabatlas/storage/artifact.h"
#include "fabatlas/v1/job.pb.h"
#include "fabatlas/v1/tasks.pb.h"

namespace fabatlas::storage {
class JobStore;
class BlobStore;
}  // namespace fabatlas::storage

namespace fabatlas::coordinator {

// The job's inputs as the artifact stores them.
storage::JobBundle PlainBundle(const v1::JobBundle& bundle);
// And back (e.g. to protocol::Materialize an artifact's bundle).
v1::JobBundle ProtoBundle(const storage::JobBundle& bundle);

// The artifact of a job whose sampling finished: manifest (design name and
// hash, code version, sampling parameters, statistics), the form and the
// bundle, and the starting points (AddStartingPoints). No cache: AddCache
// adds it when the samples' subtrees are known.
storage::Artifact ArtifactOf(const v1::JobBundle& bundle, const std::string& design_name,
                             const sampling::JobFile& job, const sampling::Form& form);

// One subtree root evaluation reported for a sample (design::SubtreeRecord /
// storage::SubtreeUse reduced to what the cache plan needs).
struct CacheSubtree {
  std::string key;                    // (τ, ρ) cache key
  std::string op;                     // the root's operation
  std::vector<std::string> children;  // child keys, in tree order
  std::int64_t bytes = 0;             // level-set memory
  bool stored = true;                 // its geometry is available through grid_of
};

struct CacheAssembly {
  std::vector<CacheSubtree> subtrees;      // any order, repeated keys allowed
  std::vector<std::string> sample_roots;   // root subtree key of every valid sample
  // Strategy, memory budget and threshold (docs/cache.md); record_curve is
  // forced on.
  cache::CacheOptions options;
  // The exact integer program is solved (and H_opt's gap to it reported,
  // never published) when it has at most this many variables; 0 = never.
  std::int64_t exact_max_variables = 5000;
  double exact_time_limit_seconds = 10;
  // Serialized geometry::Solid of a stored subtree (the blob). Throws or
  // returns "" when missing (then the entry is left out and counted).
  std::function<std::string(const std::string& key)> grid_of;
  // Leave the entries' geometry out of memory: AddCache sets
  // Artifact::cache_geometry (grid_of + glTF per entry when it is written),
  // so the writer holds one entry at a time; grid_of must then stay valid
  // until WriteArtifact, which counts the entries and the missing ones.
  bool stream_geometry = false;
  // Store H_rfree's entries beyond H_opt too (for measuring t_rfree, Fab
  // Forms Fig. 14). H_rfree has no budget, so this can make the artifact as
  // large as H_TOP; without it only H_opt's geometry is stored and the
  // manifest still records H_rfree's size. Job file: cache.store_rfree.
  bool store_rfree = false;
};

struct CacheAssemblySummary {
  // Cache entries with geometry (H_opt ∪ H_rfree) and chosen subtrees whose
  // geometry was missing; with stream_geometry: the entries planned and 0
  // (storage::ArtifactWriteSummary has the counts).
  std::int64_t entries = 0;
  std::int64_t missing = 0;
  v1::CachePlanExact exact;  // the report's exact optimum (not in the artifact)
};

// The input of the cache plan task (tasks.proto CachePlanInput): the
// assembly's subtrees, sample roots and options. Deterministic bytes for
// equal assemblies.
v1::CachePlanInput CachePlanInputOf(const CacheAssembly& assembly);

// Fab Forms Sec. 6 on the artifact, from a plan the cache plan task computed
// (protocol::RunCachePlan on CachePlanInputOf(assembly), on a worker or in
// process): fills manifest.cache (strategy, budget, threshold, H_TOP, H_opt,
// H_rfree), the Fig. 13 curves of NAIVE, OPT-AVE and OPT-MAX, and stores
// every subtree of H_opt ∪ H_rfree as an entry (grid from assembly.grid_of +
// glTF binary mesh) with its membership flags. The plan's costs are the
// deterministic model of docs/cache.md, so the artifact stays byte-identical.
CacheAssemblySummary AddCache(storage::Artifact& artifact, const CacheAssembly& assembly,
                              const v1::CachePlanReport& report);

// The same with the plan computed here, in process (`fabatlas sample`):
// AddCache(artifact, assembly, protocol::RunCachePlan(CachePlanInputOf(assembly))).
CacheAssemblySummary AddCache(storage::Artifact& artifact, const CacheAssembly& assembly);

// H_opt's memory budget when the job file gives no cache.budget_mb, in MiB
// of level-set memory (design::SubtreeRecord::bytes). A viewer holds H_opt
// in memory, so this bounds `fabatlas serve` and the artifact's size.
inline constexpr std::uint64_t kDefaultCacheBudgetMb = 256;

// The job file's `cache:` section (docs/job-format.md):
//   cache:
//     strategy: opt_max     # naive | opt_ave | opt_max
//     budget_mb: 512        # memory budget of H_opt (default: kDefaultCacheBudgetMb)
//     min_subtree_seconds: 0.1  # subtrees whose model root cost (docs/cache.md)
//                               # is lower are never cached; cluster workers
//                               # also upload only subtrees this slow
//     store_rfree: false    # also store H_rfree beyond H_opt (StoresRfree)
// Throws InputError "<job file>: cache: ..." for unknown keys or bad values.
cache::CacheOptions CacheOptionsOf(const sampling::JobFile& job);
// cache.store_rfree of the job file (default false); same errors.
bool StoresRfree(const sampling::JobFile& job);

// The subtrees of a form's valid samples evaluated in this process (for
// `fabatlas sample --cache`; the cluster gets them from its workers):
// every valid sample is re-evaluated as a preview (geometry only) through a
// cache that serves subtrees computed before, and every subtree's geometry
// is kept as a blob under blob_dir (content addressed, once per key).
// `grid_of` of the result reads those blobs.
CacheAssembly CollectSubtreesInProcess(const design::Design& design, const sampling::Form& form,
                                       const std::filesystem::path& blob_dir);

// The same from a cluster job's store: every subtree the workers reported
// for the job's accepted sample results (JobStore::Subtrees,
// SampleSubtreeKeys), the valid samples' roots in sample-id order, and
// geometry from the blobs the workers uploaded; a chosen subtree without a
// blob (its measured time was under the upload threshold) is computed here by
// re-evaluating a sample that contains it (geometry is deterministic, so the
// artifact does not depend on which worker measured what).
CacheAssembly CollectSubtreesFromStore(storage::JobStore& store, storage::BlobStore& blobs,
                                       const std::string& job_id, const design::Design& design,
                                       const sampling::Form& form);

// Whether a job asks for a geometry cache: its job file has a `cache:`
// section with a strategy or budget (`min_subtree_seconds` alone only sets
// what workers upload).
bool WantsCache(const sampling::JobFile& job);

// Fab Forms Sec. 7.4 starting points of the artifact's form
// (cache::ChooseStartingPoints).
void AddStartingPoints(storage::Artifact& artifact, const cache::StartingPointOptions& options = {});

// "<design name>.fabatlas", with characters other than [A-Za-z0-9._-] as '_'.
std::string ArtifactFileName(const std::string& design_name);

}  // namespace fabatlas::coordinator
