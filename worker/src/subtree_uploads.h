// Which subtree geometry a worker uploads, and when (tasks.proto "Geometry
// blobs", SubtreeRecord.blob_digest). A key's blob goes up at its second use
// on this worker, not at its first computation: most keys of a job are used
// by one sample only (every `difference` key of the holey vase's 1k prefix),
// and their blobs only filled the coordinator's state (577 KiB per sample,
// docs/benchmarks.md), while the coordinator rebuilds any kept cache entry
// that has no blob (coordinator/src/store_subtrees.h). Uses are still
// reported for every record, so the cache plan's (τ, ρ) statistics do not
// change; only which records carry a digest does.
//
// Geometry computed here (its root took at least the job's
// cache.min_subtree_seconds) waits for its key's second use. A waiting solid
// shares its memory with the evaluator's subtree cache entry of the same key
// while that cache keeps it (geometry::Solid copies share their level set);
// beyond the cache, waiting solids take at most `budget_bytes`, the oldest
// dropped first (a key dropped before its second use uploads when it is
// computed again, else never: the coordinator rebuilds it if the plan keeps
// it). Thread-safe.
#pragma once

#include <cstddef>
#include <list>
#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "fabatlas/geometry/solid.h"

namespace fabatlas::worker {

class SubtreeUploads {
 public:
  // Bytes of waiting solids (geometry::Solid::MemoryBytes) held at most; the
  // latest stays even when it alone is larger. Default 0: only the latest.
  void SetBudget(std::size_t bytes);
  // A subtree this worker computed whose root took at least the job's
  // threshold: waits for its key's second use, unless already uploaded.
  void Computed(const std::string& key, const geometry::Solid& solid);
  // Counts one use of each key (a sample's records, computed or from the
  // cache, repeats counted). Returns the waiting solids of the keys now used
  // at least twice and not yet uploaded, taken out of waiting: the caller
  // uploads each and reports its digest with Uploaded.
  std::vector<std::pair<std::string, geometry::Solid>> Used(const std::vector<std::string>& keys);
  // Records the digest of a key's uploaded blob ("" when the upload failed:
  // nothing is recorded, and the key uploads when computed again).
  void Uploaded(const std::string& key, const std::string& digest);
  // The digest of the key's uploaded blob, or "".
  std::string DigestOf(const std::string& key);
  std::size_t uploaded();       // keys uploaded
  std::size_t waiting_bytes();  // MemoryBytes of the waiting solids

 private:
  std::mutex mu_;
  std::size_t budget_ = 0, bytes_ = 0, uploaded_ = 0;
  std::map<std::string, int> uses_;                             // key -> uses reported by this worker
  std::map<std::string, std::string> digests_;                  // key -> blob digest; "" while uploading
  std::list<std::pair<std::string, geometry::Solid>> waiting_;  // front = most recent
  std::map<std::string, decltype(waiting_)::iterator> index_;
};

}  // namespace fabatlas::worker
