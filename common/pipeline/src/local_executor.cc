// Every task of a job in this process (see local_executor.h).
#include "fabatlas/pipeline/local_executor.h"

#include <map>
#include <mutex>
#include <optional>

#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/geometry/solid.h"
#include "fabatlas/precompute/design_evaluator.h"
#include "fabatlas/protocol/cache_plan.h"
#include "fabatlas/protocol/solid_blob.h"
#include "fabatlas/storage/blob_store.h"

namespace fabatlas::pipeline {

namespace {

// Serves subtrees computed before (read back from the blob store, with the
// trace evaluation offered beside them, so a hit lists its descendants) and
// keeps every new one as a blob.
class CollectingCache final : public design::SubtreeCache {
 public:
  explicit CollectingCache(storage::BlobStore& blobs) : blobs_(blobs) {}
  std::optional<design::CachedSubtree> Find(const std::string& key) override {
    std::lock_guard lock(mutex_);
    auto it = entries_.find(key);
    if (it == entries_.end()) return std::nullopt;
    return design::CachedSubtree{protocol::SolidOfBlob(blobs_.Read(it->second.digest)), it->second.trace,
                                 it->second.trace_bytes};
  }
  void Offer(const std::string& key, const design::CachedSubtree& subtree, double) override {
    {
      std::lock_guard lock(mutex_);
      if (entries_.count(key)) return;
    }
    std::string digest = blobs_.Put(protocol::SolidBlobOf(subtree.solid));
    std::lock_guard lock(mutex_);
    entries_.emplace(key, Entry{digest, subtree.trace, subtree.trace_bytes});
  }
  std::string DigestOf(const std::string& key) {
    std::lock_guard lock(mutex_);
    auto it = entries_.find(key);
    return it == entries_.end() ? std::string() : it->second.digest;
  }

 private:
  struct Entry {
    std::string digest;
    std::shared_ptr<const design::SubtreeTrace> trace;
    std::size_t trace_bytes = 0;
  };
  storage::BlobStore& blobs_;
  std::mutex mutex_;
  std::map<std::string, Entry> entries_;
};

}  // namespace

CacheAssembly CollectSubtreesInProcess(const design::Design& design, const sampling::Form& form,
                                       const std::filesystem::path& blob_dir) {
  auto blobs = std::make_shared<storage::BlobStore>(blob_dir);
  auto collecting = std::make_shared<CollectingCache>(*blobs);
  CacheAssembly a;
  design::EvaluateOptions options;
  options.cache = collecting.get();
  options.keep_solid = false;
  options.run_checks = false;
  for (const auto& sample : form.samples) {
    if (!sample.outcome.valid) continue;
    const design::SampleResult r = design::EvaluateSample(design, precompute::DesignPointOf(design, sample.u), options);
    if (r.subtrees.empty()) continue;
    for (const auto& s : r.subtrees)
      a.subtrees.push_back({s.key, s.op, s.children, static_cast<std::int64_t>(s.bytes), true});
    a.sample_roots.push_back(r.subtrees.back().key);
  }
  a.grid_of = [blobs, collecting](const std::string& key) {
    const std::string digest = collecting->DigestOf(key);
    return digest.empty() ? std::string() : protocol::GridOfBlob(blobs->Read(digest));
  };
  return a;
}

LocalExecutor::LocalExecutor(const design::Design& design, LocalExecutorOptions options)
    : design_(design), options_(std::move(options)), pool_(options_.threads) {}

LocalExecutor::~LocalExecutor() {
  if (!scratch_used_) return;
  std::error_code ignored;
  std::filesystem::remove_all(options_.scratch_dir, ignored);
}

std::vector<sampling::SampleOutcome> LocalExecutor::RunSampleTasks(const std::vector<sampling::SampleTask>& tasks,
                                                                   sampling::SampleEvaluator& evaluator,
                                                                   std::vector<sampling::TaskTiming>* timings) {
  return pool_.RunSampleTasks(tasks, evaluator, timings);
}

std::vector<sampling::GeometryChangeResult> LocalExecutor::RunGeometryChangeTasks(
    const std::vector<sampling::GeometryChangeTask>& tasks, sampling::SampleEvaluator& evaluator,
    std::vector<sampling::TaskTiming>* timings) {
  return pool_.RunGeometryChangeTasks(tasks, evaluator, timings);
}

std::vector<design::SweptVolumeResult> LocalExecutor::RunSweptVolumeTasks(const std::vector<SweptVolumeTask>& tasks) {
  std::vector<design::SweptVolumeResult> out;
  for (const auto& t : tasks) {
    try {
      out.push_back(design::ComputeSweptVolume(design_, precompute::DesignPointOf(design_, t.point.u), t.node_path));
    } catch (const std::exception&) {
      out.emplace_back();  // not computed, as a quarantined cluster task
    }
  }
  return out;
}

CacheAssembly LocalExecutor::CacheSubtrees(const sampling::Form& form) {
  scratch_used_ = true;
  return CollectSubtreesInProcess(design_, form, options_.scratch_dir);
}

v1::CachePlanReport LocalExecutor::RunCachePlan(const v1::CachePlanInput& input) {
  return protocol::RunCachePlan(input);
}

}  // namespace fabatlas::pipeline
