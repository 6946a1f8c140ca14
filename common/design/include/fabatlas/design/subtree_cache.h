// fabatlas/design/subtree_cache.h — the geometry cache interface of Fab Forms
// Sec. 6: subtrees keyed by (topology τ, resolved parameters ρ).
#pragma once

#include <cstddef>
#include <map>
#include <mutex>
#include <optional>
#include <string>

#include "fabatlas/geometry/solid.h"

namespace fabatlas::design {

// Where evaluation looks for subtree geometry before computing it, and where
// it offers what it computed. Keys are the hex SHA-256 digests of (τ, ρ)
// produced by EvaluateSample. Implementations must be thread-safe.
class SubtreeCache {
 public:
  virtual ~SubtreeCache() = default;
  virtual std::optional<geometry::Solid> Find(const std::string& key) = 0;
  // seconds: time the subtree's root took to compute from its children.
  virtual void Offer(const std::string& key, const geometry::Solid& solid, double seconds) = 0;
};

// A process-local cache: keeps every offered subtree whose root took at least
// `min_seconds` (default 0: everything), up to `max_bytes` in total; later
// offers beyond the budget are dropped (no eviction, so results never depend
// on timing of evictions).
class InMemorySubtreeCache final : public SubtreeCache {
 public:
  struct Options {
    double min_seconds = 0.0;
    std::size_t max_bytes = std::size_t{2} << 30;  // 2 GiB
  };
  InMemorySubtreeCache() : InMemorySubtreeCache(Options{}) {}
  explicit InMemorySubtreeCache(Options options) : options_(options) {}

  std::optional<geometry::Solid> Find(const std::string& key) override;
  void Offer(const std::string& key, const geometry::Solid& solid, double seconds) override;

  std::size_t hits() const;
  std::size_t misses() const;
  std::size_t entries() const;
  std::size_t bytes() const;

 private:
  Options options_;
  mutable std::mutex mutex_;
  std::map<std::string, geometry::Solid> entries_;
  std::size_t bytes_ = 0, hits_ = 0, misses_ = 0;
};

}  // namespace fabatlas::design
