#include "fabatlas/viewer/preview_cache.h"

namespace fabatlas::viewer {

std::shared_ptr<const EncodedPreview> PreviewCache::Get(std::int64_t sample,
                                                        const std::function<EncodedPreview(std::int64_t)>& compute,
                                                        bool* hit) {
  std::promise<Value> promise;
  {
    std::unique_lock<std::mutex> lock(mu_);
    const auto it = entries_.find(sample);
    if (it != entries_.end()) {
      ++stats_.hits;
      if (hit) *hit = true;
      if (it->second.ready) {
        lru_.splice(lru_.begin(), lru_, it->second.lru);
        return it->second.value.get();
      }
      std::shared_future<Value> pending = it->second.value;
      lock.unlock();
      return pending.get();  // another request is evaluating it
    }
    ++stats_.misses;
    if (hit) *hit = false;
    entries_[sample].value = promise.get_future().share();
  }
  Value value;
  try {
    value = std::make_shared<const EncodedPreview>(compute(sample));
  } catch (...) {
    std::lock_guard<std::mutex> lock(mu_);
    entries_.erase(sample);
    promise.set_exception(std::current_exception());
    throw;
  }
  std::lock_guard<std::mutex> lock(mu_);
  promise.set_value(value);
  Entry& e = entries_.at(sample);
  if (value->glb.size() > options_.max_bytes) {
    entries_.erase(sample);  // too large to keep: waiters already have it
    return value;
  }
  e.ready = true;
  lru_.push_front(sample);
  e.lru = lru_.begin();
  stats_.bytes += value->glb.size();
  Evict();
  return value;
}

void PreviewCache::Evict() {
  while (stats_.bytes > options_.max_bytes && !lru_.empty()) {
    const std::int64_t victim = lru_.back();
    lru_.pop_back();
    const auto it = entries_.find(victim);
    stats_.bytes -= it->second.value.get()->glb.size();
    entries_.erase(it);
    ++stats_.evictions;
  }
}

PreviewCache::Stats PreviewCache::stats() const {
  std::lock_guard<std::mutex> lock(mu_);
  Stats s = stats_;
  s.entries = lru_.size();
  return s;
}

}  // namespace fabatlas::viewer
