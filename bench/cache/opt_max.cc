// OPT-MAX (Fab Forms Alg. 1) on a synthetic design-like dependency graph of
// about 1e6 subtrees (tests/cache/synthetic_graphs.h). Times graph building
// and OPT-MAX without a budget (to H_rfree, recording the Fig. 13 curve) and
// under a budget of a quarter of H_rfree; median of --repeats runs, process
// CPU time and wall time.
//
//   bench_cache_opt_max [--samples 680000] [--repeats 3]
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "fabatlas/cache/optimize_cache.h"
#include "synthetic_graphs.h"

using namespace fabatlas::cache;

namespace {
double Cpu() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}
double Wall() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }
double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
}  // namespace

int main(int argc, char** argv) {
  int samples = 680000, repeats = 3;
  for (int i = 1; i + 1 < argc; i += 2) {
    std::string a = argv[i];
    if (a == "--samples") samples = std::stoi(argv[i + 1]);
    if (a == "--repeats") repeats = std::stoi(argv[i + 1]);
  }
  testing::SyntheticDesign d;
  d.parameters = 6;
  d.values = 10;
  d.parts = 4;
  d.samples = samples;
  d.seed = 7;
  testing::SyntheticGraph s = testing::MakeSyntheticGraph(d);
  std::vector<double> build_cpu, full_cpu, full_wall, budget_cpu, budget_wall;
  DependencyGraph g;
  CachePlan full, budget;
  for (int r = 0; r < repeats; ++r) {
    double c0 = Cpu();
    g = BuildDependencyGraph(s.nodes, s.samples);
    build_cpu.push_back(Cpu() - c0);
    CacheOptions o;
    o.strategy = Strategy::kOptMax;
    c0 = Cpu();
    double w0 = Wall();
    full = OptimizeCache(g, o);
    full_cpu.push_back(Cpu() - c0);
    full_wall.push_back(Wall() - w0);
    o.budget_bytes = full.cost.bytes / 4;
    c0 = Cpu();
    w0 = Wall();
    budget = OptimizeCache(g, o);
    budget_cpu.push_back(Cpu() - c0);
    budget_wall.push_back(Wall() - w0);
  }
  std::printf("graph: %lld subtrees, %lld samples, %zu edges\n", static_cast<long long>(g.node_count()),
              static_cast<long long>(g.sample_count()), g.child_ids.size());
  std::printf("build graph:            median CPU %.2f s\n", Median(build_cpu));
  std::printf(
      "OPT-MAX to H_rfree:     median CPU %.2f s, wall %.2f s (%lld steps, %lld dropped, %zu curve points, H %.1f "
      "GB)\n",
      Median(full_cpu), Median(full_wall), static_cast<long long>(full.steps), static_cast<long long>(full.dropped),
      full.curve.size(), static_cast<double>(full.cost.bytes) / 1e9);
  std::printf("OPT-MAX, 1/4 budget:    median CPU %.2f s, wall %.2f s (%lld steps, mean %.3f s, worst %.3f s)\n",
              Median(budget_cpu), Median(budget_wall), static_cast<long long>(budget.steps), budget.cost.mean_seconds,
              budget.cost.worst_seconds);
  return 0;
}
