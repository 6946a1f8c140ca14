#include "fabatlas/design/subtree_cache.h"

namespace fabatlas::design {

std::optional<CachedSubtree> InMemorySubtreeCache::Find(const std::string& key) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = entries_.find(key);
  if (it == entries_.end()) {
    ++misses_;
    return std::nullopt;
  }
  ++hits_;
  return it->second;
}

void InMemorySubtreeCache::Offer(const std::string& key, const CachedSubtree& subtree, double seconds) {
  if (seconds < options_.min_seconds) return;
  std::size_t size = subtree.MemoryBytes();
  std::lock_guard<std::mutex> lock(mutex_);
  if (entries_.count(key) || bytes_ + size > options_.max_bytes) return;
  entries_.emplace(key, subtree);
  bytes_ += size;
}

std::size_t InMemorySubtreeCache::hits() const {
  std::lock_guard<std::mutex> l(mutex_);
  return hits_;
}
std::size_t InMemorySubtreeCache::misses() const {
  std::lock_guard<std::mutex> l(mutex_);
  return misses_;
}
std::size_t InMemorySubtreeCache::entries() const {
  std::lock_guard<std::mutex> l(mutex_);
  return entries_.size();
}
std::size_t InMemorySubtreeCache::bytes() const {
  std::lock_guard<std::mutex> l(mutex_);
  return bytes_;
}

}  // namespace fabatlas::design
