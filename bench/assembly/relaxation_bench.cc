// Step-2 relaxation of each FabHacks Table 5 example: how Ceres ended it
// (termination type, iterations) and how far the relaxed target moves when
// every free parameter of the step-1 solution is moved by ±delta before the
// relaxation (a converged relaxation is reproducible). Usage:
//   assembly_relaxation_bench [--delta D] [--iterations N] [--datum MM] [--anchor K] [--target-weight W] [--active-set
//   0|1] [--only NAME] [--configs DIR]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "fabatlas/assembly/program.h"
#include "fabatlas/assembly/solve.h"
#include "fabatlas/error.h"
#include "solve_internal.h"

using namespace fabatlas::assembly;

int main(int argc, char** argv) {
  double delta = 1e-9;
  std::string dir = "configs/assemblies", only;
  SolveOptions opt;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--delta") delta = std::atof(argv[i + 1]);
    if (a == "--iterations") opt.relaxation_max_iterations = std::atoi(argv[i + 1]);
    if (a == "--datum") opt.relaxation_datum_mm = std::atof(argv[i + 1]);
    if (a == "--anchor") opt.relaxation_anchor_stiffness = std::atof(argv[i + 1]);
    if (a == "--target-weight") opt.relaxation_target_weight = std::atof(argv[i + 1]);
    if (a == "--active-set") opt.relaxation_active_set = std::atoi(argv[i + 1]) != 0;
    if (a == "--only") only = argv[i + 1];
    if (a == "--configs") dir = argv[i + 1];
  }
  const char* all[] = {
      "demo",          "toothbrush_holder", "charger_holder",     "soap_bottle_holder", "soap_bottle_holder_one_hook",
      "mug_hanger",    "bird_feeder",       "paper_towel_holder", "diaper_caddy",       "bathroom_basket",
      "clip_lights_1", "clip_lights_2",     "clip_lights_3",      "clip_lights_4",      "reading_nook"};
  std::printf(
      "| example | termination | iterations | relaxation moves target (mm, deg) | final (mm, deg) | moved at +delta "
      "(mm, deg) | moved at -delta (mm, deg) | stable | falls apart | CPU (s) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  try {
    for (const char* name : all) {
      if (!only.empty() && only != name) continue;
      const Program prog = LoadProgram(dir + "/" + name + ".yaml");
      const std::clock_t c0 = std::clock();
      const SolveSummary s = SolveAssembly(prog, opt);
      const double cpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
      double moved[2][2] = {};
      for (int k = 0; k < 2; ++k) {
        const SolveSummary q = internal::SolvePerturbedRelaxation(prog, k == 0 ? delta : -delta, opt);
        const auto& a = s.poses[prog.target];
        const auto& b = q.poses[prog.target];
        moved[k][0] = (a.translation() - b.translation()).norm();
        moved[k][1] = Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * 180 / M_PI;
      }
      std::string falls;
      for (const auto& f : s.falls_apart) falls += (falls.empty() ? "" : ", ") + f;
      std::printf("| %s | %s | %d | %.2f, %.1f | %.2f, %.1f | %.2g, %.2g | %.2g, %.2g | %s | %s | %.4f |\n", name,
                  s.relaxation_termination.c_str(), s.relaxation_iterations, s.relax_displacement_mm,
                  s.relax_rotation_deg, s.final_target_error_mm, s.final_target_error_deg, moved[0][0], moved[0][1],
                  moved[1][0], moved[1][1], s.stable ? "yes" : "no", falls.c_str(), cpu);
      std::fflush(stdout);
    }
  } catch (const fabatlas::InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return fabatlas::kExitBadInput;
  }
  return 0;
}
