// prototype_bench [--runs N] [--no-geometry] [--slides] — solve times of the
// Koo et al. examples (median wall and CPU over N runs, one thread) and, once
// each, the printable geometry: time, triangles, mesh report. --slides only:
// whether each slide's printed child runs over its travel (every 2.5 mm from
// 0 to each configuration's value) without touching its printed parent
// (swept::CollidesAtAnyPose, exact; minutes). Results in docs/benchmarks.md
// ("Works-like prototypes").
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include <cmath>
#include <map>

#include "fabatlas/mesh/mesh_report.h"
#include "fabatlas/prototype/fabricate.h"
#include "fabatlas/prototype/solve.h"
#include "fabatlas/swept/carve.h"

using namespace fabatlas;

static double Cpu() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }
static double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Each slide of `name`: its child moved along the slide against its parent.
static void Slides(const std::string& root, const char* name) {
  prototype::Prototype p = prototype::LoadPrototype(root + "/configs/prototypes/" + name + ".yaml");
  prototype::SolveSummary s = prototype::SolvePrototype(p);
  geometry::GridSpec g;
  g.voxel_size = p.fabrication.voxel;
  std::map<std::string, mesh::TriangleMesh> meshes;
  for (const auto& piece : prototype::FabricatePieces(p, s, g)) meshes[piece.name] = piece.solid.ToMesh();
  for (const prototype::Joint& j : p.joints) {
    if (j.type != prototype::JointType::kSlide) continue;
    std::vector<swept::Transform> travel;
    for (const prototype::Configuration& c : p.configurations) {
      auto it = c.values.find(j.name);
      if (it == c.values.end()) continue;
      double d =
          it->second.slide == "free" ? s.free_values.at(j.name + "@" + c.name + ".s") : std::stod(it->second.slide);
      int steps = static_cast<int>(std::ceil(std::abs(d) / 2.5));
      for (int k = 1; k <= steps; ++k) {
        swept::Transform t;
        t.translation[j.axis] = d * k / steps;
        travel.push_back(t);
      }
    }
    double c0 = Cpu();
    bool hit = swept::CollidesAtAnyPose(meshes.at(j.parent), meshes.at(j.child), travel);
    std::printf("| %s | %s | %s | %zu | %s | %.1f |\n", name, j.name.c_str(), j.on.empty() ? "cavity" : "rails",
                travel.size(), hit ? "**collides**" : "runs freely", Cpu() - c0);
    std::fflush(stdout);
  }
}

int main(int argc, char** argv) {
  int runs = 5;
  bool geometry = true;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--runs") && i + 1 < argc) runs = std::atoi(argv[++i]);
    if (!std::strcmp(argv[i], "--no-geometry")) geometry = false;
  }
  std::string root = FABATLAS_SOURCE_DIR_DEFAULT;
  for (int i = 1; i < argc; ++i)
    if (!std::strcmp(argv[i], "--slides")) {
      std::printf(
          "| example | slide | runs in | poses | printed child against its parent | CPU (s) "
          "|\n|---|---|---|---|---|---|\n");
      for (const char* name : {"cabinet", "crate_bar", "printer", "cellphone", "tablet", "toolbox", "jewellery_box"})
        Slides(root, name);
      return 0;
    }
  std::printf(
      "| example | variables | constraints | deviation (mm) | median solve wall (ms) | median solve CPU (ms) |"
      " geometry (s) | voxel (mm) | triangles | closed | manifold | self-int. | pieces |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const char* name : {"cabinet", "crate_bar", "crate_bed", "sofa_bunk", "printer", "cellphone", "tablet",
                           "toolbox", "jewellery_box"}) {
    prototype::Prototype p = prototype::LoadPrototype(root + "/configs/prototypes/" + name + ".yaml");
    std::vector<double> wall, cpu;
    prototype::SolveSummary s;
    for (int r = 0; r < runs; ++r) {
      double c0 = Cpu();
      auto t0 = std::chrono::steady_clock::now();
      s = prototype::SolvePrototype(p);
      wall.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() * 1e3);
      cpu.push_back((Cpu() - c0) * 1e3);
    }
    std::printf("| %s | %d | %d | %.2f | %.1f | %.1f |", name, s.variables, s.constraints, s.deviation, Median(wall),
                Median(cpu));
    if (geometry && s.satisfiable) {
      geometry::GridSpec g;
      g.voxel_size = p.fabrication.voxel;
      auto t0 = std::chrono::steady_clock::now();
      geometry::Solid solid = prototype::Fabricate(p, s, g);
      mesh::TriangleMesh m = solid.ToMesh();
      double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      mesh::MeshReport rep = mesh::InspectMesh(m);
      std::printf(" %.1f | %.2f | %zu | %s | %s | %s | %lld |\n", secs, g.voxel_size, m.triangles.size(),
                  rep.closed ? "yes" : "no", rep.manifold ? "yes" : "no", rep.self_intersecting ? "yes" : "no",
                  static_cast<long long>(rep.components));
    } else {
      std::printf(" – | – | – | – | – | – | – |\n");
    }
    std::fflush(stdout);
  }
  // Conflict explanation cost: the sofa bunk beyond its headrest bound.
  prototype::Prototype p =
      prototype::LoadPrototype(root + "/configs/prototypes/sofa_bunk.yaml", {{"headrest_height", 150}});
  std::vector<double> wall;
  prototype::SolveSummary s;
  for (int r = 0; r < runs; ++r) {
    auto t0 = std::chrono::steady_clock::now();
    s = prototype::SolvePrototype(p);
    wall.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() * 1e3);
  }
  std::printf(
      "\nsofa_bunk at headrest_height=150 (unsatisfiable): median %.1f ms including the deletion filter; %zu groups in "
      "the conflict\n",
      Median(wall), s.conflicts.size());
  return 0;
}
