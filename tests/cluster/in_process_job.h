// What a cluster job must publish: the job run as `fabatlas sample` runs it,
// by the pipeline in this process (pipeline::RunJob on a LocalExecutor of 2
// threads: sampling on the thread pool, subtrees re-evaluated, the cache plan
// run here). Needs fabatlas_pipeline.
#pragma once

#include <filesystem>

#include "fabatlas/pipeline/local_executor.h"
#include "fabatlas/pipeline/run_job.h"

namespace fabatlas::cluster_test {

// Runs the job file `job_path` with its outputs in `out_dir` (the artifact is
// out_dir / summary.artifact_file; subtree blobs under out_dir / "blobs").
inline pipeline::RunSummary RunInProcess(const std::filesystem::path& job_path, const std::filesystem::path& out_dir) {
  const pipeline::Job job = pipeline::ReadJob(job_path);
  pipeline::LocalExecutorOptions local;
  local.threads = 2;
  local.scratch_dir = out_dir / "blobs";
  pipeline::LocalExecutor executor(job.design, local);
  pipeline::RunOptions options;
  options.out_dir = out_dir;
  return pipeline::RunJob(job, executor, options);
}

}  // namespace fabatlas::cluster_test
