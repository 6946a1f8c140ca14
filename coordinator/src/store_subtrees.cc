// The subtrees of a cluster job's valid samples (see store_subtrees.h).
#include "store_subtrees.h"

#include <algorithm>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>

#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/geometry/solid.h"
#include "fabatlas/precompute/design_evaluator.h"
#include "fabatlas/protocol/solid_blob.h"
#include "fabatlas/sampling/point_key_text.h"
#include "fabatlas/storage/blob_store.h"
#include "fabatlas/storage/job_store.h"

namespace fabatlas::coordinator {

namespace {

// Keeps the geometry of one subtree key offered during an evaluation.
class CaptureCache final : public design::SubtreeCache {
 public:
  explicit CaptureCache(std::string key) : key_(std::move(key)) {}
  std::optional<design::CachedSubtree> Find(const std::string&) override { return std::nullopt; }
  void Offer(const std::string& key, const design::CachedSubtree& subtree, double) override {
    std::lock_guard lock(mutex_);
    if (key == key_ && grid_.empty()) grid_ = subtree.solid.Serialize();
  }
  std::string grid() {
    std::lock_guard lock(mutex_);
    return grid_;
  }

 private:
  std::string key_, grid_;
  std::mutex mutex_;
};

sampling::PointKey ParsePointKey(const std::string& text) {
  auto key = sampling::ParsePointKeyText(text);
  // A design with nothing exposed has one sample, whose key is empty.
  if (!key) throw std::runtime_error("the job store holds a malformed point key '" + text + "'");
  return *key;
}

}  // namespace

pipeline::CacheAssembly CollectSubtreesFromStore(storage::JobStore& store, storage::BlobStore& blobs,
                                                 const std::string& job_id, const design::Design& design,
                                                 const sampling::Form& form) {
  pipeline::CacheAssembly a;
  auto digests = std::make_shared<std::map<std::string, std::string>>();
  for (const auto& row : store.Subtrees(job_id)) {
    a.subtrees.push_back({row.key, row.op, row.children, row.bytes, true});
    if (!row.blob_digest.empty()) (*digests)[row.key] = row.blob_digest;
  }
  // Valid samples in id order, with the subtree keys each evaluated.
  std::map<std::int64_t, std::vector<std::string>> sample_keys;
  for (const auto& s : store.SampleSubtreeKeys(job_id)) {
    if (s.subtree_keys.empty()) continue;
    auto it = form.sample_ids.find(ParsePointKey(s.point_key));
    if (it == form.sample_ids.end() || !form.samples[it->second].outcome.valid) continue;
    sample_keys.emplace(it->second, s.subtree_keys);
  }
  for (const auto& [id, keys] : sample_keys) a.sample_roots.push_back(keys.back());
  auto samples = std::make_shared<std::map<std::int64_t, std::vector<std::string>>>(std::move(sample_keys));
  a.grid_of = [&blobs, &design, &form, digests, samples](const std::string& key) -> std::string {
    if (auto it = digests->find(key); it != digests->end() && blobs.Contains(it->second))
      return protocol::GridOfBlob(blobs.Read(it->second));  // workers upload zstd frames
    // The first valid sample (in id order) that lists the key: the plan keeps
    // only subtrees below valid samples' roots, and a sample lists every
    // descendant of what it lists (a cache hit is recorded with its
    // descendants' records, openscad_node.h SubtreeTrace).
    for (const auto& [id, keys] : *samples) {
      if (std::find(keys.begin(), keys.end(), key) == keys.end()) continue;
      CaptureCache capture(key);
      design::EvaluateOptions options;
      options.cache = &capture;
      options.keep_solid = false;
      options.run_checks = false;
      design::EvaluateSample(design, precompute::DesignPointOf(design, form.samples[id].u), options);
      return capture.grid();
    }
    return {};
  };
  return a;
}

}  // namespace fabatlas::coordinator
