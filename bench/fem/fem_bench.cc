// fem_bench: wall time and Newton iterations of the static Neo-Hookean solve
// on (1) Cook's membrane, 16 Q1 elements per edge (the deal.II program of docs/references.md),
// and (2) a ~20k-element voxel wedge-sandal heel under a person's weight
// (Fab Forms sandal check). Prints one table row per case with the median of
// the runs, wall and process CPU (user + system, all threads). Usage:
// fem_bench [cook_repeats=5] [heel_repeats=3] [solvers=cholesky,ichol,jacobi]
#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "fabatlas/fem/fem_check.h"
#include "fabatlas/fem/hex_mesh.h"
#include "fabatlas/fem/static_solve.h"

using namespace fabatlas::fem;

namespace {

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Process CPU seconds so far (user + system, summed over threads).
double CpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct Row {
  std::vector<double> wall, cpu, assembly, linear;
  int elements = 0, dofs = 0, newton = 0;
  long long cg = 0;  // conjugate-gradient iterations of the last run
  double result = 0;
};

void Print(const char* name, const Row& r, const char* result_name) {
  std::string walls, cpus;
  for (double w : r.wall) walls += (walls.empty() ? "" : " ") + std::to_string(w).substr(0, 7);
  for (double c : r.cpu) cpus += (cpus.empty() ? "" : " ") + std::to_string(c).substr(0, 7);
  std::printf("| %-34s | %6d | %6d | %8.3f | %8.3f | %8.3f | %8.3f | %3d | %6lld | %s = %.4f |\n", name, r.elements,
              r.dofs, Median(r.wall), Median(r.cpu), Median(r.assembly), Median(r.linear), r.newton, r.cg, result_name,
              r.result);
  std::printf("  runs: wall %s; cpu %s\n", walls.c_str(), cpus.c_str());
}

Row CooksMembrane16(int repeats) {
  const int n = 16;
  const HexMesh mesh = HexMeshFromQuadPatch({Vec2{0, 0}, Vec2{48, 44}, Vec2{48, 60}, Vec2{0, 44}}, n, n, 1.0, 1);
  auto id = [n](int i, int j, int k) { return i + (n + 1) * (j + (n + 1) * k); };
  BoundaryConditions bc;
  for (int j = 0; j <= n; ++j)
    for (int k = 0; k <= 1; ++k) bc.FixNode(id(0, j, k));
  for (int i = 1; i <= n; ++i)
    for (int j = 0; j <= n; ++j) bc.links.push_back({id(i, j, 1), id(i, j, 0), 2, -1.0});
  FaceTraction shear;
  shear.total_force = {0, 1.0, 0};
  for (int j = 0; j < n; ++j) shear.faces.push_back({id(n, j, 0), id(n, j + 1, 0), id(n, j + 1, 1), id(n, j, 1)});
  bc.tractions.push_back(shear);
  Row row;
  row.elements = static_cast<int>(mesh.elements.size());
  for (int r = 0; r < repeats; ++r) {
    const double c0 = CpuSeconds();
    const StaticSolveSummary s = SolveStatic(mesh, Material::FromShearPoisson(0.4225, 0.3), bc);
    row.cpu.push_back(CpuSeconds() - c0);
    if (!s.converged) std::fprintf(stderr, "cook: %s\n", s.message.c_str());
    row.wall.push_back(s.total_seconds);
    row.assembly.push_back(s.assembly_seconds);
    row.linear.push_back(s.linear_solve_seconds);
    row.newton = s.newton_iterations;
    row.dofs = s.num_free_dofs;
    row.result = s.displacements[id(n, n, 0)][1];
  }
  return row;
}

// Wedge-sandal heel, 1.5 mm voxels: 44 x 28 voxels footprint (66 x 42 mm),
// height falling from 24 voxels (36 mm) at the heel to 12 at the front, with
// an arch cut 4 voxels high under the middle. Ground contact at both ends
// (fixed), 700 N (a 71 kg person) on the top of the heel.
Row SandalHeel(int repeats, StaticSolveOptions::LinearSolver solver) {
  VoxelSolid v;
  v.voxel_size = 1.5;
  v.dims = {44, 28, 24};
  v.occupied.assign(static_cast<std::size_t>(44) * 28 * 24, 0);
  for (int k = 0; k < 24; ++k)
    for (int j = 0; j < 28; ++j)
      for (int i = 0; i < 44; ++i) {
        const double height = 24.0 - 12.0 * i / 43.0;
        const bool arch = i >= 14 && i < 34 && k < 4;
        v.occupied[v.Index(i, j, k)] = (k < height && !arch) ? 1 : 0;
      }
  FemLoadCase lc;
  lc.fixed_region.push_back({{-1, -1, -0.01}, {100, 100, 0.01}});   // ground plane z = 0
  lc.loaded_region.push_back({{-1, -1, 30.0}, {21.0, 100, 40.0}});  // top of the heel
  lc.total_force = {0, 0, -700.0};
  lc.material = Material::FromYoungPoisson(20.0, 0.4);  // MPa, EVA-like foam
  FemCheckOptions opt;
  opt.max_displacement = 2.0;
  opt.solve.linear_solver = solver;
  Row row;
  for (int r = 0; r < repeats; ++r) {
    const double c0 = CpuSeconds();
    const FemCheckResult res = RunFemCheck(v, lc, opt);
    row.cpu.push_back(CpuSeconds() - c0);
    if (!res.converged) std::fprintf(stderr, "heel: %s\n", res.reason.c_str());
    row.wall.push_back(res.seconds);
    row.assembly.push_back(res.assembly_seconds);
    row.linear.push_back(res.linear_solve_seconds);
    row.newton = res.newton_iterations;
    row.cg = res.linear_iterations;
    row.elements = res.num_elements;
    row.result = res.max_displacement;
  }
  const HexMesh mesh = HexMeshFromVoxels(v);
  row.dofs = 3 * static_cast<int>(mesh.nodes.size());
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  const int cook_repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 5;
  const int heel_repeats = argc > 2 ? std::max(1, std::atoi(argv[2])) : 3;
  const std::string solvers = argc > 3 ? argv[3] : "cholesky,ichol,jacobi";
  auto wanted = [&](const char* s) {
    return ("," + solvers + ",").find("," + std::string(s) + ",") != std::string::npos;
  };
  std::printf("median of %d (Cook) and %d (heel) runs; DOFs: free unknowns (Cook), 3 x nodes (heel)\n", cook_repeats,
              heel_repeats);
  std::printf(
      "| case | elements | DOFs | median wall s | median CPU s | assembly s | linear solve s | Newton its | CG its | "
      "result |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  Print("Cook's membrane 16/edge", CooksMembrane16(cook_repeats), "u_y(48,60) mm");
  // The heel with each linear solver, one after the other in the same run.
  using LS = StaticSolveOptions::LinearSolver;
  if (wanted("cholesky")) Print("voxel sandal heel, Cholesky", SandalHeel(heel_repeats, LS::kCholesky), "max |u| mm");
  if (wanted("ichol"))
    Print("voxel sandal heel, CG + incomplete Cholesky",
          SandalHeel(heel_repeats, LS::kConjugateGradientIncompleteCholesky), "max |u| mm");
  if (wanted("jacobi"))
    Print("voxel sandal heel, CG + Jacobi", SandalHeel(heel_repeats, LS::kConjugateGradientJacobi), "max |u| mm");
  return 0;
}
