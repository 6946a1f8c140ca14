// fabatlas/coordinator/run_tasks.h — tasks run through a coordinator's
// workers without a job file: the no-op tasks of the cluster benchmarks
// (bench/cluster) and tests. Jobs go through JobClient::Submit instead.
#pragma once

#include <string>
#include <vector>

#include "fabatlas/coordinator/coordinator.h"

namespace fabatlas::coordinator {

// Runs tasks (serialized v1::TaskPayload, keyed by `keys`) of the job
// `job_id` through the coordinator's workers and returns their serialized
// v1::TaskResults in order. Creates the job as running when it does not
// exist. Blocks until every result is in; throws InputError when the
// coordinator shuts down or the job is cancelled meanwhile. Thread-safe.
std::vector<std::string> RunTasks(Coordinator& coordinator, const std::string& job_id,
                                  const std::vector<std::string>& payloads, const std::vector<std::string>& keys);

}  // namespace fabatlas::coordinator
