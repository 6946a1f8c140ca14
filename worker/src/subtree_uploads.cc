// Which subtree geometry a worker uploads (see subtree_uploads.h).
#include "subtree_uploads.h"

namespace fabatlas::worker {

void SubtreeUploads::SetBudget(std::size_t bytes) {
  std::lock_guard lock(mu_);
  budget_ = bytes;
}

void SubtreeUploads::Computed(const std::string& key, const geometry::Solid& solid) {
  std::lock_guard lock(mu_);
  if (digests_.count(key) || index_.count(key)) return;
  waiting_.emplace_front(key, solid);
  index_[key] = waiting_.begin();
  bytes_ += solid.MemoryBytes();
  while (bytes_ > budget_ && waiting_.size() > 1) {
    bytes_ -= waiting_.back().second.MemoryBytes();
    index_.erase(waiting_.back().first);
    waiting_.pop_back();
  }
}

std::vector<std::pair<std::string, geometry::Solid>> SubtreeUploads::Used(const std::vector<std::string>& keys) {
  std::vector<std::pair<std::string, geometry::Solid>> reused;
  std::lock_guard lock(mu_);
  for (const std::string& key : keys) {
    if (++uses_[key] < 2) continue;
    auto it = index_.find(key);
    if (it == index_.end()) continue;  // uploaded, being uploaded, dropped, or under the threshold
    bytes_ -= it->second->second.MemoryBytes();
    reused.push_back(std::move(*it->second));
    waiting_.erase(it->second);
    index_.erase(it);
    digests_.emplace(key, std::string());  // being uploaded: Computed does not wait for it again
  }
  return reused;
}

void SubtreeUploads::Uploaded(const std::string& key, const std::string& digest) {
  std::lock_guard lock(mu_);
  if (digest.empty()) {
    digests_.erase(key);
    return;
  }
  digests_[key] = digest;
  ++uploaded_;
}

std::string SubtreeUploads::DigestOf(const std::string& key) {
  std::lock_guard lock(mu_);
  auto it = digests_.find(key);
  return it == digests_.end() ? std::string() : it->second;
}

std::size_t SubtreeUploads::uploaded() {
  std::lock_guard lock(mu_);
  return uploaded_;
}

std::size_t SubtreeUploads::waiting_bytes() {
  std::lock_guard lock(mu_);
  return bytes_;
}

}  // namespace fabatlas::worker
