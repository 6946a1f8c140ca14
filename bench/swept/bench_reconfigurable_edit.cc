// Collision detection per edit on a reconfigurable design (Reconfigurables, Sec. 5:
// collisions are re-detected in the background after every edit). Loads a
// design with a collision_free check (default: configs/designs/bench_table.yaml),
// applies a fixed sequence of parameter edits (random points of the exposed
// box, seed 11) and re-evaluates the sample after each with a subtree cache
// shared across edits, as an interactive session would. Prints per edit the
// time to re-check all transitions (the collision_free check: meshing the
// objects, spacetime collision detection, minimum clearance), the whole
// sample, and the outcome; then medians.
// Usage: bench_reconfigurable_edit [design.yaml] [edits=20]
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "fabatlas/design/design.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/design/subtree_cache.h"

using namespace fabatlas;

namespace {

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double ProcessCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string file = argc > 1 ? argv[1] : std::string(FABATLAS_SOURCE_DIR) + "/configs/designs/bench_table.yaml";
  const int edits = argc > 2 ? std::max(1, std::atoi(argv[2])) : 20;
  const design::Design d = design::LoadDesign(file);
  design::InMemorySubtreeCache cache;
  design::EvaluateOptions options;
  options.cache = &cache;
  std::mt19937 rng(11);
  std::vector<double> check_wall, sample_wall, sample_cpu;
  std::printf(
      "| edit | point | collision_free s | sample wall s | sample CPU s | outcome |\n|---|---|---|---|---|---|\n");
  for (int e = 0; e < edits; ++e) {
    design::Point u;
    std::string where;
    for (const auto& p : d.exposed) {
      std::uniform_real_distribution<double> pick(p.min, p.max);
      u[p.name] = std::round(pick(rng));
      where += (where.empty() ? "" : ", ") + p.name + "=" + std::to_string(static_cast<int>(u[p.name]));
    }
    const double cpu0 = ProcessCpuSeconds();
    const auto t0 = std::chrono::steady_clock::now();
    const design::SampleResult r = design::EvaluateSample(d, u, options);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double cpu = ProcessCpuSeconds() - cpu0;
    double check = 0;
    std::string outcome = r.valid ? "valid" : r.failure;
    for (const auto& c : r.checks)
      if (c.name == "collision_free") {
        check = c.seconds;
        if (c.measures.count("min_clearance") && r.valid)
          outcome += ", clearance " + std::to_string(c.measures.at("min_clearance")).substr(0, 6) + " mm";
        if (c.measures.count("collision_t_begin"))
          outcome += ", t in [" + std::to_string(c.measures.at("collision_t_begin")).substr(0, 5) + ", " +
                     std::to_string(c.measures.at("collision_t_end")).substr(0, 5) + "]";
      }
    check_wall.push_back(check);
    sample_wall.push_back(wall);
    sample_cpu.push_back(cpu);
    std::printf("| %d | %s | %.3f | %.3f | %.3f | %s |\n", e + 1, where.c_str(), check, wall, cpu, outcome.c_str());
  }
  std::printf(
      "\nmedian over %d edits: collision_free %.3f s wall, sample %.3f s wall, %.3f s CPU; subtree cache %zu hits, %zu "
      "misses\n",
      edits, Median(check_wall), Median(sample_wall), Median(sample_cpu), cache.hits(), cache.misses());
  return 0;
}
