// Measured preview times (see preview_times.h).
#include "fabatlas/precompute/preview_times.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>

#include "fabatlas/cache/cost_model.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/precompute/design_evaluator.h"

namespace fabatlas::precompute {

std::vector<std::vector<double>> RandomValidPoints(const sampling::Form& form, int count, std::uint64_t seed) {
  std::vector<std::vector<double>> points;
  if (count <= 0 || form.dimensions.empty()) return points;
  const sampling::DesignSpace space = form.space();
  const int n = space.dimension_count();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const std::int64_t max_draws = std::int64_t{100} * count;
  std::vector<double> u(n);
  for (std::int64_t draw = 0; draw < max_draws && static_cast<int>(points.size()) < count; ++draw) {
    for (int d = 0; d < n; ++d) {
      const auto& dim = space.dimension(d);
      switch (dim.kind) {
        case sampling::DimensionKind::kReal:
          u[d] = dim.lo + (dim.hi - dim.lo) * unit(rng);
          break;
        case sampling::DimensionKind::kInteger:
          u[d] = std::floor(dim.lo + (dim.hi - dim.lo + 1) * unit(rng));
          u[d] = std::min(u[d], dim.hi);
          break;
        case sampling::DimensionKind::kEnumerated:
          u[d] = std::min<double>(std::floor(static_cast<double>(dim.values.size()) * unit(rng)),
                                  static_cast<double>(dim.values.size() - 1));
          break;
      }
    }
    if (sampling::InEstimatedValidRegion(form, space, u)) points.push_back(u);
  }
  return points;
}

std::optional<design::CachedSubtree> FrozenSubtreeCache::Find(const std::string& key) {
  auto it = entries_.find(key);
  if (it == entries_.end()) return std::nullopt;
  return design::CachedSubtree{it->second};
}

PreviewTimes MeasurePreviewTimes(const design::Design& design, const std::vector<std::vector<double>>& points,
                                 design::SubtreeCache* cache) {
  PreviewTimes t;
  design::EvaluateOptions options;
  options.cache = cache;
  options.keep_solid = false;
  options.run_checks = false;
  options.lookup_before_children = true;
  for (const auto& u : points) {
    const design::Point p = DesignPointOf(design, u);
    const auto start = std::chrono::steady_clock::now();
    const design::SampleResult r = design::EvaluateSample(design, p, options);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!r.valid) ++t.failures;
    t.seconds.push_back(s);
    t.worst_seconds = std::max(t.worst_seconds, s);
    t.mean_seconds += s;
    // The plan's cost of each subtree this preview computed (hits cost 0).
    std::map<std::string, std::size_t> bytes;
    for (const auto& record : r.subtrees) bytes[record.key] = std::max(bytes[record.key], record.bytes);
    double predicted = 0;
    for (const auto& record : r.subtrees) {
      if (record.from_cache) continue;
      std::uint64_t in = 0;
      for (const auto& c : record.children) in += bytes.count(c) ? bytes[c] : 0;
      const double model = cache::ModelSubtreeSeconds(record.op, record.bytes, in);
      predicted += model;
      OperationCost& op = t.operations[record.op];
      ++op.subtrees;
      op.measured_seconds += record.seconds;
      op.model_seconds += model;
    }
    t.predicted_seconds.push_back(predicted);
    t.predicted_worst_seconds = std::max(t.predicted_worst_seconds, predicted);
    t.predicted_mean_seconds += predicted;
  }
  if (!t.seconds.empty()) {
    t.mean_seconds /= static_cast<double>(t.seconds.size());
    t.predicted_mean_seconds /= static_cast<double>(t.seconds.size());
  }
  return t;
}

}  // namespace fabatlas::precompute
