// The worker's shelf of root solids: the root solids the evaluator's memory
// of level sets dropped, as blob bytes (protocol/solid_blob.h, zstd: several
// times smaller than the level set; compressed as they leave that memory,
// job_cache.h), least recently used dropped first once the budget is
// exceeded. ΔG tasks take their solids from here when the evaluator's
// memory no longer holds them, and solids are shared from here as they are
// (worker.proto ShareSolids). Thread-safe.
#pragma once

#include <cstddef>
#include <list>
#include <map>
#include <mutex>
#include <optional>
#include <string>

#include "fabatlas/sampling/design_space.h"

namespace fabatlas::worker {

class SolidShelf {
 public:
  // Bytes held at most; the most recent blob stays even when it alone is
  // larger. Default 0: only the latest blob is held.
  void SetBudget(std::size_t bytes);
  // Puts the blob of the sample at `key`, or marks an already held one as
  // the most recent (its bytes are not replaced).
  void Put(const sampling::PointKey& key, std::string blob);
  // Whether the blob at `key` is held (its recency unchanged).
  bool Holds(const sampling::PointKey& key);
  // The blob at `key` (now the most recent), if held.
  std::optional<std::string> Get(const sampling::PointKey& key);
  // Bytes held.
  std::size_t bytes();

 private:
  std::mutex mu_;
  std::size_t budget_ = 0, bytes_ = 0;
  std::list<std::pair<sampling::PointKey, std::string>> lru_;  // front = most recent
  std::map<sampling::PointKey, decltype(lru_)::iterator> index_;
};

}  // namespace fabatlas::worker
