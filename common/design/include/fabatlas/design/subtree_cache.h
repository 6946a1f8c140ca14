// fabatlas/design/subtree_cache.h — the geometry cache interface of Fab Forms
// Sec. 6: subtrees keyed by (topology τ, resolved parameters ρ).
#pragma once

#include <cstddef>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "fabatlas/geometry/solid.h"

namespace fabatlas::design {

// What evaluation keeps beside a subtree's geometry so that the subtree,
// found again in the cache, is recorded and checked as when it was computed:
// the records of its descendants (an `openscad` node's CSG subtrees, looked
// up before their children) and the meshes that entered it from outside
// fabatlas (what the watertight check inspects). Built and read by
// evaluation only (common/design/src/openscad_node.h); caches keep it with
// the entry, opaque, so it lives and dies with the entry.
struct SubtreeTrace;

// One cache entry.
struct CachedSubtree {
  geometry::Solid solid{};
  std::shared_ptr<const SubtreeTrace> trace{};  // null: nothing beyond the geometry
  std::size_t trace_bytes = 0;                  // memory `trace` holds, its meshes included

  // The solid's memory plus the trace's: what a budgeted cache counts.
  std::size_t MemoryBytes() const { return solid.MemoryBytes() + trace_bytes; }
};

// Where evaluation looks for subtree geometry before computing it, and where
// it offers what it computed. Keys are the hex SHA-256 digests of (τ, ρ)
// produced by EvaluateSample. A cache that keeps an entry returns it whole
// (trace included); one filled elsewhere (an artifact's) returns solids
// without traces, and a hit is then recorded without its descendants.
// Implementations must be thread-safe.
class SubtreeCache {
 public:
  virtual ~SubtreeCache() = default;
  virtual std::optional<CachedSubtree> Find(const std::string& key) = 0;
  // seconds: time the subtree's root took to compute from its children.
  virtual void Offer(const std::string& key, const CachedSubtree& subtree, double seconds) = 0;
};

// A process-local cache: keeps every offered subtree whose root took at least
// `min_seconds` (default 0: everything), up to `max_bytes` in total
// (CachedSubtree::MemoryBytes, traces included); later offers beyond the
// budget are dropped with their traces (no eviction, so results never depend
// on timing of evictions).
class InMemorySubtreeCache final : public SubtreeCache {
 public:
  struct Options {
    double min_seconds = 0.0;
    std::size_t max_bytes = std::size_t{2} << 30;  // 2 GiB
  };
  InMemorySubtreeCache() : InMemorySubtreeCache(Options{}) {}
  explicit InMemorySubtreeCache(Options options) : options_(options) {}

  std::optional<CachedSubtree> Find(const std::string& key) override;
  void Offer(const std::string& key, const CachedSubtree& subtree, double seconds) override;

  std::size_t hits() const;
  std::size_t misses() const;
  std::size_t entries() const;
  std::size_t bytes() const;  // of the entries kept, traces included

 private:
  Options options_;
  mutable std::mutex mutex_;
  std::map<std::string, CachedSubtree> entries_;
  std::size_t bytes_ = 0, hits_ = 0, misses_ = 0;
};

}  // namespace fabatlas::design
