#include "fabatlas/precompute/design_evaluator.h"

#include <vector>

#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/error.h"

namespace fabatlas::precompute {
sampling::DesignSpace DesignSpaceOf(const design::Design& d, int subdivisions) {
  std::vector<sampling::Dimension> dims;
  for (const auto& p : d.exposed) {
    sampling::Dimension dim;
    dim.name = p.name;
    dim.lo = p.min;
    dim.hi = p.max;
    switch (p.kind) {
      case design::ParameterKind::kReal:
        dim.kind = sampling::DimensionKind::kReal;
        break;
      case design::ParameterKind::kInteger:
        dim.kind = sampling::DimensionKind::kInteger;
        break;
      case design::ParameterKind::kEnumerated:
        dim.kind = sampling::DimensionKind::kEnumerated;
        dim.values = p.labels;
        break;
    }
    dims.push_back(dim);
  }
  return sampling::DesignSpace(dims, subdivisions);
}

design::Point DesignPointOf(const design::Design& d, const std::vector<double>& u) {
  if (u.size() != d.exposed.size())
    throw InputError(d.file.string() + ": a sample has " + std::to_string(u.size()) + " coordinates, the design " +
                     std::to_string(d.exposed.size()) + " exposed parameters");
  design::Point p;
  for (std::size_t i = 0; i < u.size(); ++i) p[d.exposed[i].name] = u[i];
  return p;
}

// The evaluator's subtree cache, telling on_subtree_computed about every
// subtree offered to it (EvaluateSample offers exactly what it computed).
class DesignSampleEvaluator::ObservedCache final : public design::SubtreeCache {
 public:
  ObservedCache(design::SubtreeCache& inner, const DesignEvaluatorOptions& options)
      : inner_(inner), options_(options) {}
  std::optional<design::CachedSubtree> Find(const std::string& key) override { return inner_.Find(key); }
  void Offer(const std::string& key, const design::CachedSubtree& subtree, double seconds) override {
    options_.on_subtree_computed(key, subtree.solid, seconds);
    inner_.Offer(key, subtree, seconds);
  }

 private:
  design::SubtreeCache& inner_;
  const DesignEvaluatorOptions& options_;
};

DesignSampleEvaluator::DesignSampleEvaluator(design::Design design, DesignEvaluatorOptions options)
    : design_(std::move(design)),
      options_(std::move(options)),
      subtrees_(design::InMemorySubtreeCache::Options{options_.min_subtree_seconds, options_.subtree_memory_bytes}) {
  if (options_.on_subtree_computed) observed_ = std::make_unique<ObservedCache>(subtrees_, options_);
}

design::SampleResult DesignSampleEvaluator::Evaluate(const sampling::SamplePoint& point) {
  design::EvaluateOptions eval;
  eval.cache = observed_ ? observed_.get() : static_cast<design::SubtreeCache*>(&subtrees_);
  eval.confine_model_files = options_.confine_model_files;
  design::SampleResult r = design::EvaluateSample(design_, DesignPointOf(design_, point.u), eval);
  if (r.valid) Remember(point.key, r.solid);
  return r;
}

sampling::SampleOutcome DesignSampleEvaluator::EvaluateSample(const sampling::SamplePoint& point) {
  design::SampleResult r = Evaluate(point);
  sampling::SampleOutcome out;
  out.valid = r.valid;
  out.failure_type = r.failure;
  out.properties = r.properties;
  return out;  // cpu_seconds is the executor's to measure (sample_evaluator.h)
}

double DesignSampleEvaluator::GeometryChange(const sampling::SamplePoint& a, const sampling::SamplePoint& b) {
  return geometry::DeltaG(SolidOf(a), SolidOf(b));
}

std::size_t DesignSampleEvaluator::solid_bytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return bytes_;
}

std::size_t DesignSampleEvaluator::reevaluations() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return reevaluations_;
}

std::optional<geometry::Solid> DesignSampleEvaluator::RememberedSolid(const sampling::PointKey& key) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = index_.find(key);
  if (it == index_.end()) return std::nullopt;
  lru_.splice(lru_.begin(), lru_, it->second);
  return it->second->second;
}

geometry::Solid DesignSampleEvaluator::SolidOf(const sampling::SamplePoint& point) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = index_.find(point.key);
    if (it != index_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second);
      return it->second->second;
    }
    ++reevaluations_;
  }
  // Dropped from memory: evaluate again (deterministic). Invalid samples have
  // no solid; the sampler only asks for valid pairs.
  design::SampleResult r = Evaluate(point);
  return r.valid ? r.solid : geometry::Solid();
}

void DesignSampleEvaluator::Remember(const sampling::PointKey& key, const geometry::Solid& solid) {
  const std::size_t budget =
      options_.solid_memory_budget ? options_.solid_memory_budget() : options_.solid_memory_bytes;
  std::vector<std::pair<sampling::PointKey, geometry::Solid>> dropped;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (index_.count(key)) return;
    lru_.emplace_front(key, solid);
    index_[key] = lru_.begin();
    bytes_ += solid.MemoryBytes();
    while (bytes_ > budget && lru_.size() > 1) {
      bytes_ -= lru_.back().second.MemoryBytes();
      index_.erase(lru_.back().first);
      if (options_.on_solid_dropped) dropped.push_back(std::move(lru_.back()));
      lru_.pop_back();
    }
  }
  for (const auto& [k, s] : dropped) options_.on_solid_dropped(k, s);
}

}  // namespace fabatlas::precompute
