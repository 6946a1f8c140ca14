// The FEM validity check of Fab Forms (sandal): voxel hexahedra, fixed and
// loaded regions, max displacement under a threshold. docs/fem.md.
#include "fabatlas/fem/fem_check.h"

#include <chrono>
#include <cstdio>
#include <string>

namespace fabatlas::fem {

bool AxisBox::Contains(const Vec3& p, double tol) const {
  for (int i = 0; i < 3; ++i) {
    if (p[i] < min[i] - tol || p[i] > max[i] + tol) return false;
  }
  return true;
}

namespace {

bool InAny(const std::vector<AxisBox>& boxes, const Vec3& p, double tol) {
  for (const auto& b : boxes)
    if (b.Contains(p, tol)) return true;
  return false;
}

std::string Format(const char* fmt, double a, double b) {
  char buf[160];
  std::snprintf(buf, sizeof buf, fmt, a, b);
  return buf;
}

}  // namespace

FemCheckResult RunFemCheck(const VoxelSolid& solid, const FemLoadCase& load, const FemCheckOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const HexMesh mesh = HexMeshFromVoxels(solid);
  FemCheckResult r;
  r.num_elements = static_cast<int>(mesh.elements.size());
  auto empty = [&](const char* what) {
    r.empty_load_case = true;
    r.reason = what;
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
  };
  if (mesh.elements.empty()) return empty("the solid has no occupied voxel");
  const double tol = 1e-6 * solid.voxel_size;

  BoundaryConditions bc;
  for (int n = 0; n < static_cast<int>(mesh.nodes.size()); ++n) {
    if (InAny(load.fixed_region, mesh.nodes[n], tol)) bc.FixNode(n);
  }
  if (bc.dirichlet.empty()) return empty("the fixed region selects no node of the solid");

  FaceTraction traction;
  traction.total_force = load.total_force;
  for (const auto& face : BoundaryFaces(mesh)) {
    bool inside = false;
    for (const auto& box : load.loaded_region) {
      bool all = true;
      for (int a : face) all = all && box.Contains(mesh.nodes[a], tol);
      if (all) {
        inside = true;
        break;
      }
    }
    if (inside) traction.faces.push_back(face);
  }
  if (traction.faces.empty()) return empty("the loaded region selects no boundary face of the solid");
  bc.tractions.push_back(traction);

  const StaticSolveSummary s = SolveStatic(mesh, load.material, bc, options.solve);
  r.converged = s.converged;
  r.max_displacement = s.max_displacement;
  r.max_strain = s.max_principal_strain;
  r.newton_iterations = s.newton_iterations;
  r.assembly_seconds = s.assembly_seconds;
  r.linear_solve_seconds = s.linear_solve_seconds;
  r.linear_iterations = s.linear_iterations;
  if (!s.converged) {
    r.reason = "static solve did not converge: " + s.message;
  } else if (s.max_displacement > options.max_displacement) {
    r.reason =
        Format("max displacement %.4g mm exceeds the threshold %.4g mm", s.max_displacement, options.max_displacement);
  } else if (options.max_strain > 0 && s.max_principal_strain > options.max_strain) {
    r.reason =
        Format("max principal strain %.4g exceeds the threshold %.4g", s.max_principal_strain, options.max_strain);
  }
  r.passed = r.reason.empty();
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace fabatlas::fem
