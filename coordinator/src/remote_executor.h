// The pipeline's executor on the cluster (pipeline/executor.h): every task
// of a job becomes a durable task row keyed by content (protocol/tasks.h),
// leased to workers through Coordinator::Impl::RunTasks; internal to
// fabatlas_coordinator.
#pragma once

#include <chrono>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "coordinator_state.h"
#include "fabatlas/pipeline/executor.h"
#include "fabatlas/pipeline/run_job.h"
#include "fabatlas/protocol/job_bundle.h"

namespace fabatlas::coordinator {

// Lease affinity of a sample batch (docs/protocol.md): the batch of `tasks`
// tasks (sorted by point key) cut into contiguous runs, one per worker in
// `workers` (id, slots) in proportion to its slots, so that neighbouring
// samples, which share subtrees and ΔG edges, mostly land on one worker.
// Result[i]: the worker task i prefers; all empty with fewer than two workers.
std::vector<std::vector<std::string>> SampleBatchAffinity(std::size_t tasks,
                                                          const std::vector<std::pair<std::string, int>>& workers);

// pipeline::Executor whose tasks run on the workers.
class RemoteExecutor : public pipeline::Executor {
 public:
  // bundle_digest: the job's bundle blob (JobRecord::bundle_digest).
  RemoteExecutor(Coordinator::Impl& impl, std::string job_id, std::string bundle_digest, const pipeline::Job& job)
      : impl_(impl),
        job_id_(std::move(job_id)),
        bundle_digest_(std::move(bundle_digest)),
        job_(job),
        digest_(protocol::EvaluationDigest(job.bundle)),
        subdivisions_(job.file.subdivisions),
        sampling_(job.file.sampling) {}

  std::vector<sampling::SampleOutcome> RunSampleTasks(const std::vector<sampling::SampleTask>& tasks,
                                                      sampling::SampleEvaluator&,
                                                      std::vector<sampling::TaskTiming>* timings) override;

  std::vector<sampling::GeometryChangeResult> RunGeometryChangeTasks(
      const std::vector<sampling::GeometryChangeTask>& tasks, sampling::SampleEvaluator&,
      std::vector<sampling::TaskTiming>* timings) override;

  // Sampling is over: the ETA is the publishing left, and the job's
  // shared solids are forgotten.
  void SamplingFinished() override;
  // When SamplingFinished was called.
  std::chrono::steady_clock::time_point publish_started() const { return publish_started_; }

  // TASK_KIND_SWEPT_VOLUME tasks; each worker uploads its cutter surface
  // as a blob, read back here.
  std::vector<design::SweptVolumeResult> RunSweptVolumeTasks(
      const std::vector<pipeline::SweptVolumeTask>& tasks) override;

  // The subtrees the workers reported while sampling. Every subtree blob
  // the store names is still here (the collector keeps a running job's
  // geometry); one that is not is evaluated again, and recorded.
  pipeline::CacheAssembly CacheSubtrees(const sampling::Form& form) override;

  v1::CachePlanReport RunCachePlan(const v1::CachePlanInput& input) override;

  // Any tasks, run by the workers; results in
  // order. preferred: lease affinity per task (may be empty); producers:
  // the worker whose result was accepted ("" = already in the store).
  std::vector<v1::TaskResult> Run(const std::vector<v1::TaskPayload>& payloads,
                                  const std::vector<std::vector<std::string>>& preferred = {},
                                  std::vector<std::string>* producers = nullptr);

 private:
  // The schedule for the ETA (JobStatus.eta_seconds, job_eta.h): every
  // batch with its evaluator CPU, handed to the status calls.
  void BeginBatch(bool samples, std::size_t size);
  void EndBatch(const std::vector<v1::TaskResult>& results);
  void Publish(bool batch_begins);

  Coordinator::Impl& impl_;
  std::string job_id_, bundle_digest_;
  const pipeline::Job& job_;
  std::string digest_;
  int subdivisions_;
  sampling::SamplingOptions sampling_;
  // The worker that evaluated each sample in this run of the driver (it
  // holds the root solid in memory), for ΔG lease affinity and solid
  // sharing (TaskPayload.solid_holder_a/b).
  std::map<sampling::PointKey, std::string> holders_;
  std::vector<EtaBatch> batches_;
  std::size_t dims_ = 1;
  std::chrono::steady_clock::time_point publish_started_;
};

}  // namespace fabatlas::coordinator
