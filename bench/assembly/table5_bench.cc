// Full-solve time of each FabHacks Table 5 example (pre-checks + two-step
// solve), median of N runs, side by side with the published Python times
// (data/fabhacks/EXAMPLES.md). Usage:
//   assembly_table5_bench [--runs N] [--configs DIR] [--only NAME] [--poses]
#include <algorithm>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "fabatlas/assembly/program.h"
#include "fabatlas/assembly/solve.h"
#include "fabatlas/error.h"

using namespace fabatlas::assembly;

int main(int argc, char** argv) {
  int runs = 5;
  std::string dir = "configs/assemblies", only;
  bool poses = false;
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "--poses") poses = true;  // print every part's step-1 and relaxed position
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::string(argv[i]) == "--only") only = argv[i + 1];
    if (std::string(argv[i]) == "--runs") runs = std::atoi(argv[i + 1]);
    if (std::string(argv[i]) == "--configs") dir = argv[i + 1];
  }
  struct Example {
    const char* file;
    const char* label;
    double published_s;
  };
  const std::vector<Example> examples = {
      {"demo", "demo", 10.0},          {"toothbrush_holder", "toothbrush", 15.6},
      {"charger_holder", "charger", 2.0}, {"soap_bottle_holder", "soap bottle", 26.9},
      {"mug_hanger", "mug hanger", 5.2}, {"bird_feeder", "bird feeder", 45.7},
      {"paper_towel_holder", "paper towel", 20.5}, {"diaper_caddy", "diaper caddy", 50.8},
      {"bathroom_basket", "bathroom basket", 28.2}, {"clip_lights_1", "clip lights 1", 30.8},
      {"clip_lights_2", "clip lights 2", 28.3}, {"clip_lights_3", "clip lights 3", 19.2},
      {"clip_lights_4", "clip lights 4", 18.7}};
  std::printf("| example | feasible | stable | target err step1 (mm) | final (mm, deg) | starts | median CPU (s) | median wall (s) | published (s) | speed-up (CPU) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  try {
    for (const auto& ex : examples) {
      if (!only.empty() && only != ex.file) continue;
      const Program prog = LoadProgram(dir + "/" + ex.file + ".yaml");
      std::vector<double> t;
      SolveSummary s;
      std::vector<double> cpu;
      for (int r = 0; r < runs; ++r) {
        const std::clock_t c0 = std::clock();  // process CPU time: the solve is single-threaded
        s = SolveAssembly(prog);
        cpu.push_back(static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC);
        t.push_back(s.seconds);
      }
      std::sort(t.begin(), t.end());
      std::sort(cpu.begin(), cpu.end());
      const double med = cpu[cpu.size() / 2], wall = t[t.size() / 2];
      std::printf("| %s | %s | %s | %.2f | %.2f, %.1f%s | %d | %.4f | %.4f | %.1f | %.0fx |\n", ex.label,
                  s.feasible ? "yes" : "NO", s.stable ? "yes" : "no", s.step1_target_error_mm,
                  s.final_target_error_mm, s.final_target_error_deg, prog.target_match_rotation ? "" : " (pos only)",
                  s.starts_tried, med, wall, ex.published_s, ex.published_s / med);
      for (const auto& m : s.messages) std::printf("    note: %s\n", m.c_str());
      for (const auto& f : s.falls_apart) std::printf("    falls apart: %s\n", f.c_str());
      for (std::size_t i = 0; poses && i < s.poses.size(); ++i) {
        const auto a = s.step1_poses.empty() ? s.poses[i].translation() : s.step1_poses[i].translation();
        const auto b = s.poses[i].translation();
        std::printf("    %s: step 1 [%.1f, %.1f, %.1f] relaxed [%.1f, %.1f, %.1f]\n", prog.instances[i].name.c_str(), a.x(),
                    a.y(), a.z(), b.x(), b.y(), b.z());
      }
    }
  } catch (const fabatlas::InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return fabatlas::kExitBadInput;
  }
  return 0;
}
