// fabatlas/precompute/design_evaluator.h — a real design as the sampler's
// evaluator: EvaluateSample(u) of Fab Forms Alg. 2 and ΔG of Eq. 2 on level
// sets, behind the plain-data sampling::SampleEvaluator interface that local
// thread pools and cluster workers both drive.
#pragma once

#include <cstddef>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "fabatlas/design/design.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/design/subtree_cache.h"
#include "fabatlas/geometry/solid.h"
#include "fabatlas/sampling/design_space.h"
#include "fabatlas/sampling/sample_evaluator.h"

namespace fabatlas::precompute {

// The design space U of a design: one sampling dimension per exposed
// parameter, in the design's order (real -> real, integer -> integer,
// enum -> enumerated with the design's labels).
sampling::DesignSpace DesignSpaceOf(const design::Design& design, int subdivisions);

// A sampling point's coordinates as a design point (by parameter name).
design::Point DesignPointOf(const design::Design& design, const std::vector<double>& u);

struct DesignEvaluatorOptions {
  // Root solids of valid samples kept for ΔG, least recently used dropped
  // first. A ΔG whose sample was dropped re-evaluates it (results are
  // deterministic, so only time is lost).
  std::size_t solid_memory_bytes = std::size_t{1} << 30;
  // When set, the budget of root solids asked at each insertion instead of
  // solid_memory_bytes (a budget shared with other memory, as the cluster
  // worker's with its shelf of compressed solids). Must be thread-safe.
  std::function<std::size_t()> solid_memory_budget;
  // Called for every root solid dropped from memory (least recently used
  // over the budget), with its sample's key, on the thread that remembered
  // the solid that pushed it out and outside the evaluator's lock; the
  // cluster worker compresses it onto its shelf here. Must be thread-safe.
  std::function<void(const sampling::PointKey& key, const geometry::Solid& solid)> on_solid_dropped;
  // Subtree cache shared by all evaluations (Fab Forms Sec. 6): subtrees whose
  // root took at least min_subtree_seconds are kept.
  std::size_t subtree_memory_bytes = std::size_t{512} << 20;
  double min_subtree_seconds = 0.0;
  // Called on the evaluating thread for every subtree this evaluator computes
  // (not for cache hits), with its cache key, geometry and the seconds its
  // root took from its children. Cluster workers upload slow subtrees from
  // here (tasks.proto "Geometry blobs"). Must be thread-safe.
  std::function<void(const std::string& key, const geometry::Solid& solid, double seconds)> on_subtree_computed;
  // design::EvaluateOptions::confine_model_files (the cluster worker: a job
  // bundle is all an evaluation reads).
  bool confine_model_files = false;
};

// Thread-safe: the executor calls it from several threads at once.
class DesignSampleEvaluator final : public sampling::SampleEvaluator {
 public:
  DesignSampleEvaluator(design::Design design, DesignEvaluatorOptions options = {});

  sampling::SampleOutcome EvaluateSample(const sampling::SamplePoint& point) override;
  double GeometryChange(const sampling::SamplePoint& a, const sampling::SamplePoint& b) override;

  // EvaluateSample of Fab Forms Alg. 2 through the subtree cache, with the
  // whole result (root solid, subtree records, checks); remembers the root
  // solid of a valid sample for later ΔG.
  design::SampleResult Evaluate(const sampling::SamplePoint& point);
  // The remembered root solid of the valid sample at `key`, if still in
  // memory (no evaluation).
  std::optional<geometry::Solid> RememberedSolid(const sampling::PointKey& key);
  // Remembers a root solid obtained elsewhere (e.g. downloaded from the
  // coordinator's blob store) for later ΔG.
  void Remember(const sampling::PointKey& key, const geometry::Solid& solid);
  // The root solid of the sample at `point`: remembered, else evaluated again
  // (empty for an invalid sample).
  geometry::Solid SolidOf(const sampling::SamplePoint& point);

  const design::Design& design() const { return design_; }
  std::size_t reevaluations() const;
  // Memory held: remembered root solids and the subtree cache, bytes.
  std::size_t solid_bytes() const;
  std::size_t subtree_bytes() const { return subtrees_.bytes(); }

 private:
  class ObservedCache;

  design::Design design_;
  DesignEvaluatorOptions options_;
  design::InMemorySubtreeCache subtrees_;
  std::unique_ptr<design::SubtreeCache> observed_;  // subtrees_ + on_subtree_computed
  mutable std::mutex mutex_;
  std::list<std::pair<sampling::PointKey, geometry::Solid>> lru_;  // front = most recent
  std::map<sampling::PointKey, decltype(lru_)::iterator> index_;
  std::size_t bytes_ = 0, reevaluations_ = 0;
};

}  // namespace fabatlas::precompute
