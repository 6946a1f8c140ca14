// calculix_cantilever: fabatlas against CalculiX (ccx, Debian calculix-ccx)
// on the same problem, side by side in one run. The slender cantilever of
// docs/fem.md (L = 200 mm, 4 x 4 mm section, E = 1000 MPa, nu = 0, voxel
// hexahedra, clamped end face, dead tip load P = alpha E I / L^2 as
// consistent nodal forces on the end face, compressible Neo-Hookean) is
// written as a CalculiX input (*HYPERELASTIC, NEO HOOKE with C10 = mu/2,
// D1 = 2/kappa; *STEP, NLGEOM; *STATIC with the whole load as the first
// increment, like fabatlas' single load step with cutbacks) and solved with
// C3D8 and C3D8I; fabatlas solves it with Q1 and incompatible modes. For
// each: median CPU seconds (user + system, the ccx child process or this
// process) and the mean vertical tip displacement, against the elastica
// (Mattiasson 1981: v/L = 0.30172 at alpha = 1, 0.60325 at alpha = 3).
// The two volumetric energies differ (ccx: (J-1)^2/D1, fabatlas:
// (kappa/4)(J^2 - 1 - 2 ln J)) only at second order in the volume change.
//
// Usage: calculix_cantilever [repeats=3] [voxel_mm=1] [alphas=1,3] [workdir=/tmp]
#include <sys/resource.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "fabatlas/fem/hex_mesh.h"
#include "fabatlas/fem/static_solve.h"

using namespace fabatlas::fem;

namespace {

constexpr double kL = 200, kH = 4, kE = 1000, kNu = 0;

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double CpuSeconds(int who) {
  rusage u{};
  getrusage(who, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct Cantilever {
  HexMesh mesh;
  std::vector<int> clamped, tip;
  std::vector<NodalForce> forces;  // consistent nodal forces of the tip traction
  bool print_all = false;          // print U of every node (max |u|), not only the tip
};

Cantilever MakeCantilever(double voxel, double alpha) {
  Cantilever c;
  VoxelSolid v;
  v.voxel_size = voxel;
  v.dims = {static_cast<int>(kL / voxel + 0.5), static_cast<int>(kH / voxel + 0.5), static_cast<int>(kH / voxel + 0.5)};
  v.occupied.assign(static_cast<std::size_t>(v.dims[0]) * v.dims[1] * v.dims[2], 1);
  c.mesh = HexMeshFromVoxels(v);
  const double P = alpha * kE * (kH * kH * kH * kH / 12) / (kL * kL);
  std::map<int, double> share;  // node -> fraction of the end-face area
  for (const auto& f : BoundaryFaces(c.mesh)) {
    bool on_end = true;
    for (int a : f) on_end = on_end && c.mesh.nodes[a][0] == kL;
    if (on_end)
      for (int a : f) share[a] += 0.25 * voxel * voxel / (kH * kH);
  }
  for (const auto& [n, s] : share) c.forces.push_back({n, {0, 0, -P * s}});
  for (int n = 0; n < static_cast<int>(c.mesh.nodes.size()); ++n) {
    if (c.mesh.nodes[n][0] == 0.0) c.clamped.push_back(n);
    if (c.mesh.nodes[n][0] == kL) c.tip.push_back(n);
  }
  return c;
}

void WriteInp(const Cantilever& c, const std::string& type, const std::string& path, double E = kE, double nu = kNu) {
  const Material m = Material::FromYoungPoisson(E, nu);
  std::ofstream o(path);
  o.precision(17);
  o << "*HEADING\nfabatlas cantilever\n*NODE\n";
  for (std::size_t n = 0; n < c.mesh.nodes.size(); ++n)
    o << n + 1 << ", " << c.mesh.nodes[n][0] << ", " << c.mesh.nodes[n][1] << ", " << c.mesh.nodes[n][2] << "\n";
  o << "*ELEMENT, TYPE=" << type << ", ELSET=EALL\n";
  for (std::size_t e = 0; e < c.mesh.elements.size(); ++e) {
    o << e + 1;
    for (int a : c.mesh.elements[e]) o << ", " << a + 1;
    o << "\n";
  }
  o << "*NSET, NSET=CLAMP\n";
  for (int n : c.clamped) o << n + 1 << ",\n";
  if (c.print_all) {
    o << "*NSET, NSET=NALL, GENERATE\n1, " << c.mesh.nodes.size() << ", 1\n";
  }
  o << "*NSET, NSET=TIP\n";
  for (int n : c.tip) o << n + 1 << ",\n";
  o << "*BOUNDARY\nCLAMP, 1, 3\n";
  o << "*MATERIAL, NAME=NH\n*HYPERELASTIC, NEO HOOKE\n" << m.mu / 2 << ", " << 2 / m.kappa << "\n";
  o << "*SOLID SECTION, ELSET=EALL, MATERIAL=NH\n";
  o << "*STEP, NLGEOM, INC=1000\n*STATIC\n1., 1.\n*CLOAD\n";
  for (const auto& f : c.forces) o << f.node + 1 << ", 3, " << f.force[2] << "\n";
  o << "*NODE PRINT, NSET=" << (c.print_all ? "NALL" : "TIP") << "\nU\n*END STEP\n";
}

// Mean u_z over the TIP set in the last block of the .dat file.
double ReadDatTip(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::vector<double> last;
  std::vector<double> cur;
  while (std::getline(in, line)) {
    if (line.find("displacements") != std::string::npos) {
      if (!cur.empty()) last = cur;
      cur.clear();
      continue;
    }
    std::istringstream s(line);
    int node;
    double ux, uy, uz;
    if (s >> node >> ux >> uy >> uz) cur.push_back(uz);
  }
  if (!cur.empty()) last = cur;
  double sum = 0;
  for (double z : last) sum += z;
  return last.empty() ? 0 : -sum / last.size();
}

// Largest |u| over the nodes of the last block of the .dat file.
double ReadDatMaxU(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  double cur = 0, last = 0;
  while (std::getline(in, line)) {
    if (line.find("displacements") != std::string::npos) {
      last = std::max(last, cur);
      cur = 0;
      continue;
    }
    std::istringstream s(line);
    int node;
    double ux, uy, uz;
    if (s >> node >> ux >> uy >> uz) cur = std::max(cur, std::sqrt(ux * ux + uy * uy + uz * uz));
  }
  return std::max(last, cur);
}

// The two end-loaded blocks of tests/fem/fem_check_test.cc (1 mm voxels,
// clamped x = 0 face, 0.5 N along -z spread uniformly over the x = length
// face, E = 100 MPa, nu = 0.3) solved by ccx C3D8I: its max |u| is the
// test's peer value.
void FemCheckTestPeers(const std::string& dir) {
  for (int length : {8, 60}) {
    const int side = length == 8 ? 8 : 3;
    Cantilever c;
    VoxelSolid v;
    v.voxel_size = 1;
    v.dims = {length, side, side};
    v.occupied.assign(static_cast<std::size_t>(length) * side * side, 1);
    c.mesh = HexMeshFromVoxels(v);
    c.print_all = true;
    std::map<int, double> share;
    for (const auto& f : BoundaryFaces(c.mesh)) {
      bool on_end = true;
      for (int a : f) on_end = on_end && c.mesh.nodes[a][0] == length;
      if (on_end)
        for (int a : f) share[a] += 0.25 / (side * side);
    }
    for (const auto& [n, s] : share) c.forces.push_back({n, {0, 0, -0.5 * s}});
    for (int n = 0; n < static_cast<int>(c.mesh.nodes.size()); ++n) {
      if (c.mesh.nodes[n][0] == 0.0) c.clamped.push_back(n);
      if (c.mesh.nodes[n][0] == length) c.tip.push_back(n);
    }
    for (const std::string type : {"C3D8I", "C3D8"}) {
      const std::string job = "block" + std::to_string(length) + "_" + type;
      WriteInp(c, type, dir + "/" + job + ".inp", 100.0, 0.3);
      const std::string cmd = "cd '" + dir + "' && OMP_NUM_THREADS=1 ccx -i " + job + " > " + job + ".log 2>&1";
      const int status = std::system(cmd.c_str());
      std::printf("fem_check_test block %d x %d x %d mm, ccx %s: max |u| = %.6g mm%s\n", length, side, side,
                  type.c_str(), ReadDatMaxU(dir + "/" + job + ".dat"), status ? " (ccx failed)" : "");
    }
  }
}

struct Result {
  std::vector<double> cpu;
  double tip = 0;
  std::string note;
};

Result RunCcx(const Cantilever& c, const std::string& type, const std::string& dir, int repeats) {
  Result r;
  const std::string job = dir + "/cant_" + type;
  WriteInp(c, type, job + ".inp");
  for (int k = 0; k < repeats; ++k) {
    const double c0 = CpuSeconds(RUSAGE_CHILDREN);
    const std::string cmd =
        "cd '" + dir + "' && OMP_NUM_THREADS=1 ccx -i cant_" + type + " > cant_" + type + ".log 2>&1";
    const int status = std::system(cmd.c_str());
    r.cpu.push_back(CpuSeconds(RUSAGE_CHILDREN) - c0);
    if (status != 0) r.note = "ccx exit status " + std::to_string(WEXITSTATUS(status)) + " (see " + job + ".log)";
  }
  r.tip = ReadDatTip(job + ".dat");
  return r;
}

Result RunFabatlas(const Cantilever& c, StaticSolveOptions::Element element, int repeats) {
  Result r;
  BoundaryConditions bc;
  for (int n : c.clamped) bc.FixNode(n);
  bc.nodal_forces = c.forces;
  StaticSolveOptions o;
  o.element = element;
  o.load_steps = 1;  // the whole load, halved on failure (as ccx's increment control)
  for (int k = 0; k < repeats; ++k) {
    const double c0 = CpuSeconds(RUSAGE_SELF);
    const StaticSolveSummary s = SolveStatic(c.mesh, Material::FromYoungPoisson(kE, kNu), bc, o);
    r.cpu.push_back(CpuSeconds(RUSAGE_SELF) - c0);
    double uz = 0;
    for (int n : c.tip) uz += s.displacements[n][2];
    r.tip = -uz / c.tip.size();
    char note[200];
    std::snprintf(note, sizeof note,
                  "%d Newton its, %d factorisations, %d load steps; wall: assembly %.2f s, linear %.2f s, total %.2f s",
                  s.newton_iterations, s.factorizations, s.load_steps_taken, s.assembly_seconds, s.linear_solve_seconds,
                  s.total_seconds);
    r.note = s.converged ? note : s.message;
  }
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 3;
  const double voxel = argc > 2 ? std::atof(argv[2]) : 1.0;
  std::vector<double> alphas;
  {
    std::stringstream s(argc > 3 ? argv[3] : "1,3");
    std::string item;
    while (std::getline(s, item, ',')) alphas.push_back(std::atof(item.c_str()));
  }
  const std::string dir = argc > 4 ? argv[4] : "/tmp";
  if (argc > 5 && std::string(argv[5]) == "fem_check_test") {
    FemCheckTestPeers(dir);
    return 0;
  }
  const std::map<double, double> elastica = {{1.0, 0.30172}, {2.0, 0.49346}, {3.0, 0.60325}};
  double load[3] = {0, 0, 0};
  std::printf("cantilever L=200 h=4 E=1000 nu=0, voxel %.3g mm (%d through the thickness), median of %d runs\n", voxel,
              static_cast<int>(kH / voxel + 0.5), repeats);
  std::printf("| alpha | solver, element | elements | median CPU s | tip u_z mm | vs elastica | runs CPU s | note |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (double alpha : alphas) {
    const Cantilever c = MakeCantilever(voxel, alpha);
    const double ref = elastica.count(alpha) ? kL * elastica.at(alpha) : 0;
    auto row = [&](const char* name, const Result& r) {
      std::string runs;
      for (double t : r.cpu) runs += (runs.empty() ? "" : " ") + std::to_string(t).substr(0, 6);
      std::printf("| %.0f | %s | %zu | %.3f | %.4f | %+.3f%% | %s | %s |\n", alpha, name, c.mesh.elements.size(),
                  Median(r.cpu), r.tip, ref > 0 ? 100 * (r.tip / ref - 1) : 0.0, runs.c_str(), r.note.c_str());
    };
    row("CalculiX C3D8", RunCcx(c, "C3D8", dir, repeats));
    row("fabatlas Q1", RunFabatlas(c, StaticSolveOptions::Element::kQ1, repeats));
    row("CalculiX C3D8I", RunCcx(c, "C3D8I", dir, repeats));
    row("fabatlas incompatible modes", RunFabatlas(c, StaticSolveOptions::Element::kIncompatibleModes, repeats));
  }
  if (getloadavg(load, 3) == 3) std::printf("load average %.2f %.2f %.2f\n", load[0], load[1], load[2]);
  return 0;
}
