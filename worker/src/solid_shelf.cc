// The worker's shelf of root solids (see solid_shelf.h).
#include "solid_shelf.h"

namespace fabatlas::worker {

void SolidShelf::SetBudget(std::size_t bytes) {
  std::lock_guard lock(mu_);
  budget_ = bytes;
}

void SolidShelf::Put(const sampling::PointKey& key, std::string blob) {
  std::lock_guard lock(mu_);
  if (auto it = index_.find(key); it != index_.end()) {
    lru_.splice(lru_.begin(), lru_, it->second);
    return;
  }
  bytes_ += blob.size();
  lru_.emplace_front(key, std::move(blob));
  index_[key] = lru_.begin();
  while (bytes_ > budget_ && lru_.size() > 1) {
    bytes_ -= lru_.back().second.size();
    index_.erase(lru_.back().first);
    lru_.pop_back();
  }
}

bool SolidShelf::Holds(const sampling::PointKey& key) {
  std::lock_guard lock(mu_);
  return index_.count(key) > 0;
}

std::size_t SolidShelf::bytes() {
  std::lock_guard lock(mu_);
  return bytes_;
}

std::optional<std::string> SolidShelf::Get(const sampling::PointKey& key) {
  std::lock_guard lock(mu_);
  auto it = index_.find(key);
  if (it == index_.end()) return std::nullopt;
  lru_.splice(lru_.begin(), lru_, it->second);
  return it->second->second;
}

}  // namespace fabatlas::worker
