// Each FabHacks Table 5 example (the same programs, PARTS.md §4), its
// columns measured like for like: full solve (pre-checks + feasibility +
// step 1 + relaxation), quick reject (the pre-checks), number of starts until
// the cycles close ("# initial guesses") and the time spent closing them
// ("constraints checking"); medians of N runs, beside the published Python
// times (MacBook Pro M1, averages of 10 runs). Usage:
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
    double published_s, quick_reject_s, guesses, checking_s;  // FabHacks Table 5 (-1: "-")
  };
  const std::vector<Example> examples = {{"demo", "demo", 9.997, -1, -1, -1},
                                         {"toothbrush_holder", "toothbrush holder", 15.551, 0.003, 1.0, 2.027},
                                         {"charger_holder", "charger holder", 2.014, 0.001, 1.4, 0.743},
                                         {"soap_bottle_holder", "soap bottle holder", 26.937, 0.003, 1.0, 1.536},
                                         {"mug_hanger", "mug hanger", 5.188, -1, -1, -1},
                                         {"bird_feeder", "bird feeder", 45.734, -1, -1, -1},
                                         {"paper_towel_holder", "paper towel holder", 20.479, 0.002, 2.3, 8.251},
                                         {"diaper_caddy", "diaper caddy", 50.839, 0.002, 1.3, 8.227},
                                         {"bathroom_basket", "bathroom basket", 28.151, -1, -1, -1},
                                         {"clip_lights_1", "clip lights 1", 30.820, -1, -1, -1},
                                         {"clip_lights_2", "clip lights 2", 28.293, -1, -1, -1},
                                         {"clip_lights_3", "clip lights 3", 19.182, -1, -1, -1},
                                         {"clip_lights_4", "clip lights 4", 18.685, -1, -1, -1},
                                         {"reading_nook", "reading nook", 742.279, 0.0146, 3.1, 336.741}};
  auto pub = [](double v, const char* fmt) {
    static char buf[8][32];
    static int k = 0;
    k = (k + 1) % 8;
    if (v < 0) return "-";
    std::snprintf(buf[k], sizeof buf[k], fmt, v);
    return static_cast<const char*>(buf[k]);
  };
  std::printf(
      "| example | parts | cycles | feasible | stable | full solve CPU (s) | published (s) | speed-up | quick reject "
      "(s) | published | starts to close | published | closing (s) | published | target step 1 / final (mm) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  try {
    for (const auto& ex : examples) {
      if (!only.empty() && only != ex.file) continue;
      const Program prog = LoadProgram(dir + "/" + ex.file + ".yaml");
      SolveSummary s;
      std::vector<double> cpu, pre, feas;
      for (int r = 0; r < runs; ++r) {
        const std::clock_t c0 = std::clock();  // process CPU time: the solve is single-threaded
        s = SolveAssembly(prog);
        cpu.push_back(static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC);
        pre.push_back(s.precheck_seconds);
        feas.push_back(s.feasibility_seconds);
      }
      auto median = [](std::vector<double> v) {
        std::sort(v.begin(), v.end());
        return v[v.size() / 2];
      };
      int cycles = 0;
      for (const auto& c : prog.connections) cycles += c.closing ? 1 : 0;
      const double med = median(cpu);
      std::printf("| %s | %zu | %d | %s | %s | %.4f | %.3f | %.0fx | %s | %s | %s | %s | %s | %s | %.1f / %.1f |\n",
                  ex.label, prog.instances.size(), cycles, s.feasible ? "yes" : "NO", s.stable ? "yes" : "no", med,
                  ex.published_s, ex.published_s / med, cycles ? pub(median(pre), "%.5f") : "-",
                  pub(ex.quick_reject_s, "%.4f"), cycles ? pub(s.feasibility_starts, "%.0f") : "-",
                  pub(ex.guesses, "%.1f"), cycles ? pub(median(feas), "%.4f") : "-", pub(ex.checking_s, "%.3f"),
                  s.step1_target_error_mm, s.final_target_error_mm);
      std::fflush(stdout);
      for (const auto& m : s.messages) std::printf("    note: %s\n", m.c_str());
      for (const auto& f : s.falls_apart) std::printf("    falls apart: %s\n", f.c_str());
      for (std::size_t i = 0; poses && i < s.poses.size(); ++i) {
        const auto a = s.step1_poses.empty() ? s.poses[i].translation() : s.step1_poses[i].translation();
        const auto b = s.poses[i].translation();
        std::printf("    %s: step 1 [%.1f, %.1f, %.1f] relaxed [%.1f, %.1f, %.1f]\n", prog.instances[i].name.c_str(),
                    a.x(), a.y(), a.z(), b.x(), b.y(), b.z());
      }
    }
  } catch (const fabatlas::InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return fabatlas::kExitBadInput;
  }
  return 0;
}
