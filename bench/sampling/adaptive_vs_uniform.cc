// Adaptive sampling (Fab Forms Sec. 5.2) vs a uniform grid on designs whose
// valid region is known in closed form: samples each needs to reach an IoU
// >= 0.95 between the estimated valid region (all-valid cells / leaves) and
// the true one, side by side in one run. Then the sampling overhead (wall
// time outside evaluator calls) with an evaluator that burns a realistic CPU
// time per call. Results: docs/benchmarks.md (Sampling).
//
// Usage: bench_sampling_adaptive_vs_uniform [--threshold T] [--burn-ms MS]
//        [--repeats K] [--iou-points P (0: skip)] [--subdivisions S] [--overhead-depth D]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
#include <string>
#include <time.h>
#include <vector>

#include "analytic_designs.h"

using namespace fabatlas::sampling;
using namespace fabatlas::sampling::testing;

namespace {

struct Reach {
  long long samples = -1;
  int setting = -1;  // grid subdivisions (uniform) or max_depth (adaptive)
  double iou = 0;
};

template <class Eval, class Truth>
Reach UniformToTarget(Eval& ev, Truth truth, double target, int points, int first_n, int max_n) {
  ThreadPoolExecutor ex(1);
  for (int n = first_n; n <= max_n; ++n) {
    DesignSpace space(Eval::Dimensions(), n);
    SamplingOptions o;
    o.max_depth = 0;
    auto s = SampleDesignSpace(space, ev, ex, o);
    const double iou = EstimatedRegionIoU(s.form, truth, points);
    if (iou >= target) return {s.statistics.samples, n, iou};
  }
  return {};
}

template <class Eval, class Truth>
Reach AdaptiveToTarget(Eval& ev, Truth truth, double target, int points, double threshold, int subdivisions,
                       int first_depth) {
  ThreadPoolExecutor ex(1);
  for (int depth = first_depth; depth <= 30; ++depth) {
    DesignSpace space(Eval::Dimensions(), subdivisions);
    SamplingOptions o;
    o.max_depth = depth;
    o.dg_threshold = threshold;
    auto s = SampleDesignSpace(space, ev, ex, o);
    const double iou = EstimatedRegionIoU(s.form, truth, points);
    if (iou >= target) return {s.statistics.samples, depth, iou};
  }
  return {};
}

// Burns `ms` of thread CPU time per call on top of the analytic answer.
class BurningEvaluator : public SampleEvaluator {
 public:
  BurningEvaluator(SampleEvaluator& inner, double sample_ms, double change_ms)
      : inner_(inner), sample_ms_(sample_ms), change_ms_(change_ms) {}
  SampleOutcome EvaluateSample(const SamplePoint& p) override {
    Burn(sample_ms_);
    return inner_.EvaluateSample(p);
  }
  double GeometryChange(const SamplePoint& a, const SamplePoint& b) override {
    Burn(change_ms_);
    return inner_.GeometryChange(a, b);
  }

 private:
  static double Cpu() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
  }
  static void Burn(double ms) {
    const double end = Cpu() + ms * 1e-3;
    volatile double x = 0;
    while (Cpu() < end)
      for (int i = 0; i < 1000; ++i) x = x + 1e-9 * i;
  }
  SampleEvaluator& inner_;
  double sample_ms_, change_ms_;
};

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

}  // namespace

int main(int argc, char** argv) {
  double threshold = 0.5, burn_ms = 20.0;
  int repeats = 5, points = 200000, subdivisions = 5, overhead_depth = 3;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--threshold"))
      threshold = std::atof(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--burn-ms"))
      burn_ms = std::atof(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--repeats"))
      repeats = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--iou-points"))
      points = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--subdivisions"))
      subdivisions = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--overhead-depth"))
      overhead_depth = std::atoi(argv[i + 1]);
    else {
      std::fprintf(stderr, "unknown option %s\n", argv[i]);
      return 2;
    }
  }
  std::printf("IoU by Monte Carlo, %d points (seed 12345); adaptive: subdivisions %d, dg_threshold %.3g\n\n", points,
              subdivisions, threshold);
  std::printf(
      "| design | IoU target | uniform samples (grid n, IoU) | adaptive samples (max_depth, IoU) | adaptive / uniform "
      "|\n");
  std::printf("|---|---|---|---|---|\n");
  auto row = [&](const char* name, double target, const Reach& u, const Reach& a) {
    std::printf("| %s | %.2f | %lld (n=%d, %.4f) | %lld (depth %d, %.4f) | %.3f |\n", name, target, u.samples,
                u.setting, u.iou, a.samples, a.setting, a.iou, double(a.samples) / double(u.samples));
    std::fflush(stdout);
  };
  // One design's rows: the fewest samples each method needs to reach each
  // IoU target (uniform grids of up to max_n per axis).
  auto reach = [&](const char* name, auto ev, const auto& truly_valid, std::initializer_list<double> targets,
                   int max_n) {
    Reach u{0, 1, 0}, a{0, 0, 0};
    for (double target : targets) {
      u = UniformToTarget(ev, truly_valid, target, points, u.setting, max_n);
      a = AdaptiveToTarget(ev, truly_valid, target, points, threshold, subdivisions, a.setting);
      row(name, target, u, a);
    }
  };
  if (points > 0) {
    reach("hollow cylinder 2-D", HollowCylinder2D(), HollowCylinder2D::TrulyValid, {0.95, 0.98, 0.99}, 400);
    reach("budget cylinder 2-D", BudgetCylinder2D(), BudgetCylinder2D::TrulyValid, {0.95, 0.98}, 400);
    reach("hollow cylinder 3-D", HollowCylinder3D(), HollowCylinder3D::TrulyValid, {0.95, 0.97}, 100);
  }
  std::fflush(stdout);
  if (repeats <= 0) return 0;

  // Overhead: 3-D cylinder, max_depth --overhead-depth, evaluator burning burn_ms per sample
  // and burn_ms / 4 per ΔG.
  std::printf("\nOverhead (3-D hollow cylinder, max_depth %d, %.1f ms CPU per sample, %.1f ms per ΔG), %d repeats\n\n",
              overhead_depth, burn_ms, burn_ms / 4, repeats);
  std::printf(
      "| threads | samples | ΔG calls | job wall s (median) | sampling logic %% (median) | overhead %% (median) |\n");
  std::printf("|---|---|---|---|---|---|\n");
  for (int threads : {1, 2}) {
    std::vector<double> wall, logic, overhead;
    long long samples = 0, calls = 0;
    for (int r = 0; r < repeats; ++r) {
      HollowCylinder3D inner;
      BurningEvaluator ev(inner, burn_ms, burn_ms / 4);
      ThreadPoolExecutor ex(threads);
      DesignSpace space(HollowCylinder3D::Dimensions(), subdivisions);
      SamplingOptions o;
      o.max_depth = overhead_depth;
      o.dg_threshold = threshold;
      auto s = SampleDesignSpace(space, ev, ex, o);
      samples = s.statistics.samples;
      calls = s.statistics.geometry_change_calls;
      wall.push_back(s.statistics.wall_seconds);
      logic.push_back(100.0 * s.statistics.sampling_logic_seconds / s.statistics.wall_seconds);
      // Everything that is not evaluator work: ideal job time is the
      // evaluator wall time spread over the threads.
      const double ideal = s.statistics.evaluator_wall_seconds / threads;
      overhead.push_back(100.0 * (s.statistics.wall_seconds - ideal) / s.statistics.wall_seconds);
    }
    std::printf("| %d | %lld | %lld | %.2f | %.3f | %.2f |\n", threads, samples, calls, Median(wall), Median(logic),
                Median(overhead));
  }
  return 0;
}
