#include "fabatlas/sampling/executor.h"

#include <time.h>

#include <chrono>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace fabatlas::sampling {

namespace {
double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}
double WallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
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

std::vector<SampleOutcome> ThreadPoolExecutor::RunSampleTasks(const std::vector<SampleTask>& tasks,
                                                              SampleEvaluator& evaluator,
                                                              std::vector<TaskTiming>* timings) {
  std::vector<SampleOutcome> results(tasks.size());
  std::vector<TaskTiming> local(tasks.size());
  arena_->arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, tasks.size(), 1),
                      [&](const tbb::blocked_range<size_t>& r) {
                        for (size_t i = r.begin(); i != r.end(); ++i) {
                          const double c0 = ThreadCpuSeconds(), w0 = WallSeconds();
                          results[i] = evaluator.EvaluateSample(tasks[i].point);
                          results[i].cpu_seconds = ThreadCpuSeconds() - c0;
                          local[i].wall_seconds = WallSeconds() - w0;
                        }
                      });
  });
  if (timings) *timings = std::move(local);
  return results;
}

std::vector<GeometryChangeResult> ThreadPoolExecutor::RunGeometryChangeTasks(
    const std::vector<GeometryChangeTask>& tasks, SampleEvaluator& evaluator,
    std::vector<TaskTiming>* timings) {
  std::vector<GeometryChangeResult> results(tasks.size());
  std::vector<TaskTiming> local(tasks.size());
  arena_->arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, tasks.size(), 1),
                      [&](const tbb::blocked_range<size_t>& r) {
                        for (size_t i = r.begin(); i != r.end(); ++i) {
                          const double c0 = ThreadCpuSeconds(), w0 = WallSeconds();
                          results[i].geometry_change =
                              evaluator.GeometryChange(tasks[i].point_a, tasks[i].point_b);
                          results[i].cpu_seconds = ThreadCpuSeconds() - c0;
                          local[i].wall_seconds = WallSeconds() - w0;
                        }
                      });
  });
  if (timings) *timings = std::move(local);
  return results;
}

}  // namespace fabatlas::sampling
