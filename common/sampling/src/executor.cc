#include "fabatlas/sampling/executor.h"

#include <time.h>

#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "fabatlas/stopwatch.h"

namespace fabatlas::sampling {

namespace {
double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}
}  // namespace

struct ThreadPoolExecutor::Arena {
  explicit Arena(int n) : arena(n) {}
  tbb::task_arena arena;
};

ThreadPoolExecutor::ThreadPoolExecutor(int threads) : threads_(threads) {
  if (threads < 1) throw std::invalid_argument("ThreadPoolExecutor: threads must be >= 1");
  arena_ = std::make_unique<Arena>(threads);
}

ThreadPoolExecutor::~ThreadPoolExecutor() = default;

namespace {
// Runs run(i) for every i in [0, n) on the executor's arena, one task per
// TBB chunk, and stores each call's thread CPU time in results[i].cpu_seconds
// and its wall time in the timings.
template <class Result, class Run>
std::vector<Result> RunTimed(tbb::task_arena& arena, size_t n, Run run, std::vector<TaskTiming>* timings) {
  std::vector<Result> results(n);
  std::vector<TaskTiming> local(n);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) {
        const double c0 = ThreadCpuSeconds();
        const Stopwatch wall_time;
        run(i, results[i]);
        results[i].cpu_seconds = ThreadCpuSeconds() - c0;
        local[i].wall_seconds = wall_time.Seconds();
      }
    });
  });
  if (timings) *timings = std::move(local);
  return results;
}
}  // namespace

std::vector<SampleOutcome> ThreadPoolExecutor::RunSampleTasks(const std::vector<SampleTask>& tasks,
                                                              SampleEvaluator& evaluator,
                                                              std::vector<TaskTiming>* timings) {
  return RunTimed<SampleOutcome>(
      arena_->arena, tasks.size(),
      [&](size_t i, SampleOutcome& out) { out = evaluator.EvaluateSample(tasks[i].point); }, timings);
}

std::vector<GeometryChangeResult> ThreadPoolExecutor::RunGeometryChangeTasks(
    const std::vector<GeometryChangeTask>& tasks, SampleEvaluator& evaluator, std::vector<TaskTiming>* timings) {
  return RunTimed<GeometryChangeResult>(
      arena_->arena, tasks.size(),
      [&](size_t i, GeometryChangeResult& out) {
        out.geometry_change = evaluator.GeometryChange(tasks[i].point_a, tasks[i].point_b);
      },
      timings);
}

}  // namespace fabatlas::sampling
