// fabatlas/viewer/preview_cache.h — encoded previews kept for reuse. Every
// preview snaps to one of the form's valid samples (Fab Forms Sec. 7.3), so a
// shared customiser need evaluate each sample only once while it stays in
// this cache.
#pragma once

#include <cstdint>
#include <functional>
#include <future>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <string>

namespace fabatlas::viewer {

// A preview as sent: glTF binary bytes and what the evaluation reported.
struct EncodedPreview {
  std::int64_t sample = -1;
  std::string glb;
  double seconds = 0;  // evaluation time when it was computed
  int subtrees = 0, cache_hits = 0;
};

struct PreviewCacheOptions {
  // Total glb bytes kept; least recently used previews are dropped beyond it.
  // 0 keeps nothing (every request evaluates).
  std::size_t max_bytes = std::size_t{192} << 20;
};

// Thread-safe. Concurrent requests for a sample not yet cached wait for one
// evaluation instead of each running their own. Memory: at most max_bytes
// of glb plus one preview per evaluation in flight; lookups O(log n).
class PreviewCache {
 public:
  explicit PreviewCache(PreviewCacheOptions options = {}) : options_(options) {}

  // The cached preview of `sample`, or compute(sample)'s, stored. `hit` tells
  // which. Exceptions from compute reach every waiter; nothing is stored.
  std::shared_ptr<const EncodedPreview> Get(std::int64_t sample,
                                            const std::function<EncodedPreview(std::int64_t)>& compute,
                                            bool* hit = nullptr);

  struct Stats {
    std::int64_t hits = 0, misses = 0, evictions = 0;
    std::size_t bytes = 0, entries = 0;
  };
  Stats stats() const;

 private:
  using Value = std::shared_ptr<const EncodedPreview>;
  struct Entry {
    std::shared_future<Value> value;
    std::list<std::int64_t>::iterator lru;  // valid once ready
    bool ready = false;
  };
  void Evict();  // with mu_ held

  PreviewCacheOptions options_;
  mutable std::mutex mu_;
  std::map<std::int64_t, Entry> entries_;
  std::list<std::int64_t> lru_;  // most recent first; ready entries only
  Stats stats_;
};

}  // namespace fabatlas::viewer
