// fabatlas/pipeline/local_executor.h — every task of a job in this process
// (`fabatlas sample`): sample and ΔG tasks on a thread pool
// (sampling::ThreadPoolExecutor), swept volumes and the cache plan on the
// calling thread, and the cache plan's subtrees by evaluating the valid
// samples again (CollectSubtreesInProcess).
#pragma once

#include <filesystem>
#include <memory>

#include "fabatlas/design/design.h"
#include "fabatlas/pipeline/executor.h"
#include "fabatlas/sampling/executor.h"

namespace fabatlas::pipeline {

struct LocalExecutorOptions {
  int threads = 1;  // sample and ΔG tasks at once (>= 1)
  // Where CacheSubtrees keeps the subtrees' geometry as blobs until the
  // artifact is written; removed by the destructor. Required for
  // CacheSubtrees.
  std::filesystem::path scratch_dir;
};

class LocalExecutor final : public Executor {
 public:
  LocalExecutor(const design::Design& design, LocalExecutorOptions options);
  ~LocalExecutor() override;
  LocalExecutor(const LocalExecutor&) = delete;
  LocalExecutor& operator=(const LocalExecutor&) = delete;

  std::vector<sampling::SampleOutcome> RunSampleTasks(const std::vector<sampling::SampleTask>& tasks,
                                                      sampling::SampleEvaluator& evaluator,
                                                      std::vector<sampling::TaskTiming>* timings) override;
  std::vector<sampling::GeometryChangeResult> RunGeometryChangeTasks(
      const std::vector<sampling::GeometryChangeTask>& tasks, sampling::SampleEvaluator& evaluator,
      std::vector<sampling::TaskTiming>* timings) override;
  // design::ComputeSweptVolume per task; a task that throws gives an empty
  // result, as a quarantined cluster task does.
  std::vector<design::SweptVolumeResult> RunSweptVolumeTasks(const std::vector<SweptVolumeTask>& tasks) override;
  CacheAssembly CacheSubtrees(const sampling::Form& form) override;
  v1::CachePlanReport RunCachePlan(const v1::CachePlanInput& input) override;

 private:
  const design::Design& design_;
  LocalExecutorOptions options_;
  sampling::ThreadPoolExecutor pool_;
  bool scratch_used_ = false;
};

// The subtrees of a form's valid samples evaluated in this process: every
// valid sample is re-evaluated as a preview (geometry only) through a cache
// that serves subtrees computed before, and every subtree's geometry is kept
// as a blob under blob_dir (content addressed, once per key). `grid_of` of
// the result reads those blobs.
CacheAssembly CollectSubtreesInProcess(const design::Design& design, const sampling::Form& form,
                                       const std::filesystem::path& blob_dir);

}  // namespace fabatlas::pipeline
