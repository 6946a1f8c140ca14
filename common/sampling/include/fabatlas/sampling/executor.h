// fabatlas/sampling/executor.h — where sampling work runs.
//
// The sampler expresses all evaluator work as batches of plain-data tasks
// (no pointers into sampler state), so a cluster executor can ship them to
// remote workers (docs/protocol.md) without touching the sampling logic.
// An executor returns one result per task, in task order; the order in which
// it completes the tasks must not matter (the sampler only reads results by
// index once the whole batch is back).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "fabatlas/sampling/sample_evaluator.h"

namespace fabatlas::sampling {

// EvaluateSample(u) for one point.
struct SampleTask {
  SamplePoint point;
};

// ΔG between two valid samples, identified by their sample ids in the form
// (a < b) and given with their points.
struct GeometryChangeTask {
  std::int64_t sample_a = 0;
  std::int64_t sample_b = 0;
  SamplePoint point_a;
  SamplePoint point_b;
};

struct GeometryChangeResult {
  double geometry_change = 0.0;  // ΔG in [0, 1]
  double cpu_seconds = 0.0;      // thread CPU time of the evaluator call
};

// Every result also carries the wall time of the evaluator call (seconds),
// which the sampler uses to report its own overhead.
struct TaskTiming {
  double wall_seconds = 0.0;
};

class Executor {
 public:
  virtual ~Executor() = default;
  // Runs every task; results[i] belongs to tasks[i]; timings[i] likewise.
  virtual std::vector<SampleOutcome> RunSampleTasks(const std::vector<SampleTask>& tasks, SampleEvaluator& evaluator,
                                                    std::vector<TaskTiming>* timings) = 0;
  virtual std::vector<GeometryChangeResult> RunGeometryChangeTasks(const std::vector<GeometryChangeTask>& tasks,
                                                                   SampleEvaluator& evaluator,
                                                                   std::vector<TaskTiming>* timings) = 0;
};

// Runs tasks on `threads` threads of a private TBB task arena (threads >= 1),
// one task at a time per thread (grain size 1, tasks are expensive). The
// evaluator may itself use TBB; its parallelism nests inside the arena.
// cpu_seconds is measured with CLOCK_THREAD_CPUTIME_ID around each call.
class ThreadPoolExecutor : public Executor {
 public:
  explicit ThreadPoolExecutor(int threads);
  ~ThreadPoolExecutor() override;
  ThreadPoolExecutor(const ThreadPoolExecutor&) = delete;
  ThreadPoolExecutor& operator=(const ThreadPoolExecutor&) = delete;
  int threads() const { return threads_; }

  std::vector<SampleOutcome> RunSampleTasks(const std::vector<SampleTask>& tasks, SampleEvaluator& evaluator,
                                            std::vector<TaskTiming>* timings) override;
  std::vector<GeometryChangeResult> RunGeometryChangeTasks(const std::vector<GeometryChangeTask>& tasks,
                                                           SampleEvaluator& evaluator,
                                                           std::vector<TaskTiming>* timings) override;

 private:
  int threads_;
  struct Arena;
  std::unique_ptr<Arena> arena_;
};

}  // namespace fabatlas::sampling
