// fabatlas/precompute/preview_times.h — measured preview times of a design
// with and without a geometry cache (Fab Forms Sec. 8 "Performance
// Evaluation", Fig. 14: "actual time to compute preview across 200 design
// points ... randomly drawn from the valid region").
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "fabatlas/design/design.h"
#include "fabatlas/design/subtree_cache.h"
#include "fabatlas/sampling/form.h"

namespace fabatlas::precompute {

// `count` points drawn uniformly from the form's estimated valid region (the
// all-valid k-d leaves, Fab Forms Sec. 5.1) by rejection from the bounded
// space with a fixed seed; discrete dimensions draw whole values. Returns
// fewer points when 100 * count draws find fewer (a tiny valid region), and
// none when the region is empty.
std::vector<std::vector<double>> RandomValidPoints(const sampling::Form& form, int count, std::uint64_t seed = 1);

// A read-only subtree cache: Find() serves the loaded entries, Offer()
// ignores what evaluation offers, so every preview sees the same cache H.
class FrozenSubtreeCache final : public design::SubtreeCache {
 public:
  void Add(const std::string& key, geometry::Solid solid) { entries_[key] = std::move(solid); }
  std::size_t size() const { return entries_.size(); }
  std::optional<design::CachedSubtree> Find(const std::string& key) override;  // solids only, no traces
  void Offer(const std::string&, const design::CachedSubtree&, double) override {}

 private:
  std::map<std::string, geometry::Solid> entries_;
};

// What the subtrees of one operation cost over the previews: measured as the
// preview paid them (SubtreeRecord::seconds: the root's own time given its
// children, in this warm process) and as the cache plan models them.
struct OperationCost {
  int subtrees = 0;             // subtrees computed (cache hits excluded)
  double measured_seconds = 0;  // sum over them
  double model_seconds = 0;     // sum of cache::ModelSubtreeSeconds over them
};

struct PreviewTimes {
  std::vector<double> seconds;  // wall seconds per point (constraint solve + geometry)
  double mean_seconds = 0.0;
  double worst_seconds = 0.0;
  int failures = 0;  // points whose geometry failed (should be 0 in the valid region)
  // Per point, what the cache plan predicts this preview costs: the model
  // costs (cache::ModelSubtreeSeconds, as protocol::RunCachePlan costs a
  // key: its op, its bytes and its children's) of the subtrees the preview
  // computed, i.e. T_H(r) of Fab Forms Eq. 3 for this point and cache.
  std::vector<double> predicted_seconds;
  double predicted_mean_seconds = 0.0;
  double predicted_worst_seconds = 0.0;
  std::map<std::string, OperationCost> operations;  // by subtree op
};

// Evaluates the design at every point (parameter values in the design's
// exposed order) as a preview: constraint solve and geometry, no checks
// (design::EvaluateOptions::run_checks = false), through `cache` (nullptr =
// no cache). Times are wall seconds of each evaluation; beside them the
// plan's prediction for the same previews.
PreviewTimes MeasurePreviewTimes(const design::Design& design, const std::vector<std::vector<double>>& points,
                                 design::SubtreeCache* cache);

}  // namespace fabatlas::precompute
