// fabatlas/pipeline/executor.h — where a job's work runs: every task of the
// pipeline (run_job.h) goes through one Executor, so the same steps run in
// this process (LocalExecutor, `fabatlas sample`) or on cluster workers (the
// coordinator's remote executor, docs/protocol.md).
//
// The tasks are plain data. An executor returns one result per task, in task
// order, and the results must not depend on where or in which order the
// tasks ran: the artifact of a job is the same bytes on every executor.
#pragma once

#include <string>
#include <vector>

#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/pipeline/cache_assembly.h"
#include "fabatlas/sampling/executor.h"
#include "fabatlas/sampling/form.h"
#include "fabatlas/v1/tasks.pb.h"

namespace fabatlas::pipeline {

// The swept volume of one carve_swept node at one point
// (design::ComputeSweptVolume; tasks.proto TASK_KIND_SWEPT_VOLUME).
struct SweptVolumeTask {
  std::string node_path;  // "root/1/0" in the tree, "object:NAME/0" in an object's tree
  sampling::SamplePoint point;
};

class Executor : public sampling::Executor {
 public:
  // Sample and ΔG tasks: sampling::Executor (Fab Forms Alg. 2, Eq. 2).

  // Called once when the sampling loop has finished, before any other task
  // (e.g. to forget the solids kept for ΔG). Default: nothing.
  virtual void SamplingFinished() {}

  // The swept volume of every task, in order. A task that could not be
  // computed gives a result with empty surface_sha256 (published as
  // "computed": false).
  virtual std::vector<design::SweptVolumeResult> RunSweptVolumeTasks(const std::vector<SweptVolumeTask>& tasks) = 0;

  // The subtrees the form's valid samples evaluate and their geometry
  // (CacheAssembly without options), for the cache plan. sample_roots in
  // sample-id order.
  virtual CacheAssembly CacheSubtrees(const sampling::Form& form) = 0;

  // protocol::RunCachePlan(input), wherever it runs. Throws InputError when
  // no plan can be had (e.g. the task was quarantined).
  virtual v1::CachePlanReport RunCachePlan(const v1::CachePlanInput& input) = 0;
};

}  // namespace fabatlas::pipeline
