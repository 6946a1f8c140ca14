// fabatlas/pipeline/cache_assembly.h — the geometry cache of an artifact
// (Fab Forms Sec. 6, docs/cache.md): the subtrees the valid samples
// evaluated, the plan over them (protocol::RunCachePlan, in process or as a
// worker's TASK_KIND_CACHE_PLAN task) and the entries it keeps.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "fabatlas/cache/optimize_cache.h"
#include "fabatlas/artifact/artifact.h"
#include "fabatlas/v1/tasks.pb.h"

namespace fabatlas::pipeline {

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
  std::vector<CacheSubtree> subtrees;     // any order, repeated keys allowed
  std::vector<std::string> sample_roots;  // root subtree key of every valid sample, in sample-id order
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
  // (artifact::ArtifactWriteSummary has the counts).
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
CacheAssemblySummary AddCache(artifact::Artifact& artifact, const CacheAssembly& assembly,
                              const v1::CachePlanReport& report);

// The same with the plan computed here, in process:
// AddCache(artifact, assembly, protocol::RunCachePlan(CachePlanInputOf(assembly))).
CacheAssemblySummary AddCache(artifact::Artifact& artifact, const CacheAssembly& assembly);

// "exact worst case 1.23 s (optimal, 120 variables), H_opt gap 0.00 %", or
// "exact optimum: <why not solved>".
std::string ExactText(const v1::CachePlanExact& exact);

}  // namespace fabatlas::pipeline
