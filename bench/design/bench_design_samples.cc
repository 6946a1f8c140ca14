// Per-sample evaluation cost of each example design (Fab Forms Alg. 2: solve,
// tree, checks, properties) and the cost of one ΔG, at the designs' own
// resolution. Points are drawn uniformly from each design space with a fixed
// seed; medians are reported beside Fab Forms Table 3's per-sample CPU time.
//
// Usage: bench_design_samples [--defaults|--where] [samples per design (default 15)] [design.yaml ...]
// (defaults to configs/designs/{vase,cup,pawn,tealight}.yaml). --defaults:
// every sample at the design's default point (a worker's steady per-sample
// cost for one point, after the process's first sample; docs/benchmarks.md,
// "OpenSCAD"), and below each design's row the median wall seconds of each
// part of a sample (SampleResult::timings and every check's seconds).
// --where: random points as without a flag, and below each row where the
// evaluator's wall time goes over all samples (one process, warm after its
// first sample): total seconds per outcome (valid or failure type), per
// stage (solve, each subtree operation's own time, each check, properties)
// and for ΔG between consecutive valid samples, as shares of the total.
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "fabatlas/design/evaluate_sample.h"

using namespace fabatlas;

namespace {

double ProcessCpu() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

double Wall() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

design::Point RandomPoint(const design::Design& d, std::mt19937_64& rng) {
  design::Point u;
  for (const auto& p : d.exposed) {
    std::uniform_real_distribution<double> uni(p.min, p.max);
    double v = uni(rng);
    if (p.kind != design::ParameterKind::kReal) v = std::round(v);
    u[p.name] = v;
  }
  return u;
}

}  // namespace

int main(int argc, char** argv) {
  const bool defaults = argc > 1 && std::string(argv[1]) == "--defaults";
  const bool where = argc > 1 && std::string(argv[1]) == "--where";
  const int first = defaults || where ? 2 : 1;
  int n = argc > first ? std::atoi(argv[first]) : 15;
  std::vector<std::filesystem::path> designs;
  for (int i = first + 1; i < argc; ++i) designs.emplace_back(argv[i]);
  if (designs.empty())
    for (const char* name : {"vase", "cup", "pawn", "tealight"})
      designs.push_back(std::filesystem::path(FABATLAS_SOURCE_DIR) / "configs/designs" / (std::string(name) + ".yaml"));

  std::printf(
      "| design | voxel (mm) | samples | valid | median CPU s / sample (all) | median CPU s (valid) | median wall s "
      "(valid) | median CPU s / ΔG |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& path : designs) {
    design::Design d = design::LoadDesign(path);
    std::mt19937_64 rng(2026);
    std::vector<double> cpu_all, cpu_valid, wall_valid, cpu_dg;
    std::map<std::string, std::vector<double>> stages;             // seconds per timing and check, valid samples
    std::map<std::string, double> outcome_seconds, stage_seconds;  // --where
    std::map<std::string, int> outcome_count;
    double total_seconds = 0;
    design::SampleResult previous;
    bool have_previous = false;
    int valid = 0;
    for (int i = 0; i < n; ++i) {
      design::Point u = defaults ? design::DefaultPoint(d) : RandomPoint(d, rng);
      double c0 = ProcessCpu(), w0 = Wall();
      design::SampleResult r = design::EvaluateSample(d, u);
      double cpu = ProcessCpu() - c0, wall = Wall() - w0;
      cpu_all.push_back(cpu);
      if (where && i > 0) {  // the first sample pays the process's one-time set-up
        const std::string outcome = r.valid ? "valid" : r.failure;
        outcome_seconds[outcome] += wall;
        ++outcome_count[outcome];
        total_seconds += wall;
        stage_seconds["solve"] += r.timings["solve"];
        for (const auto& t : r.subtrees) stage_seconds["tree: " + t.op] += t.seconds;
        for (const auto& c : r.checks)
          if (c.name != "constraints" && c.name != "geometry") stage_seconds["check " + c.name] += c.seconds;
        stage_seconds["properties"] += r.timings["properties"];
      }
      if (r.valid) {
        ++valid;
        cpu_valid.push_back(cpu);
        wall_valid.push_back(wall);
        for (const auto& [name, seconds] : r.timings) stages[name].push_back(seconds);
        for (const auto& c : r.checks) stages["check " + c.name].push_back(c.seconds);
        if (have_previous) {
          double g0 = ProcessCpu();
          volatile double dg = design::DeltaG(previous, r);
          (void)dg;
          cpu_dg.push_back(ProcessCpu() - g0);
          if (where) stage_seconds["ΔG (one per valid sample)"] += cpu_dg.back();
        }
        previous = std::move(r);
        have_previous = true;
      }
    }
    std::printf("| %s | %.2f | %d | %d | %.3f | %.3f | %.3f | %.3f |\n", d.name.c_str(), d.voxel_size, n, valid,
                Median(cpu_all), Median(cpu_valid), Median(wall_valid), Median(cpu_dg));
    if (defaults) {
      std::printf("stages (median wall s of the valid samples; the checks run side by side):");
      for (const auto& [name, v] : stages) std::printf(" %s %.4f,", name.c_str(), Median(v));
      std::printf("\n");
    }
    if (where && total_seconds > 0) {
      std::printf("outcomes (samples, wall s, share):");
      for (const auto& [name, seconds] : outcome_seconds)
        std::printf(" %s %d %.2f %.1f%%,", name.c_str(), outcome_count[name], seconds, 100 * seconds / total_seconds);
      std::printf("\nstages (wall s, share of the samples' %.2f s):", total_seconds);
      for (const auto& [name, seconds] : stage_seconds)
        std::printf(" %s %.3f %.1f%%,", name.c_str(), seconds, 100 * seconds / total_seconds);
      std::printf("\n");
    }
    std::fflush(stdout);
  }
  return 0;
}
