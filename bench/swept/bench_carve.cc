// Exact (CGAL corefinement) against level-set carving of a swept volume
// (Reconfigurables, Eq. 4) on the cabinet insert (configs/designs/cabinet_insert.yaml
// at its default point): the foam block minus the 3 mm offset swept volume of
// the mug as it is stowed. The two objects come from the design itself
// (evaluated on its 3 mm grid); the carve is then timed with each method, the
// sweep and the subtraction apart, medians of the repeats, wall and process
// CPU. Usage: bench_carve [repeats=3]
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "../../common/design/src/reconfigurable.h"
#include "fabatlas/design/design.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/swept/rigid_motion.h"

using namespace fabatlas;

namespace {

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double ProcessCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// The design with its tree replaced by one object (no checks).
geometry::Solid ObjectOf(const std::string& yaml, const std::string& object) {
  std::string s = yaml;
  s = s.substr(0, s.find("\ntree:")) + "\ntree: {op: object, object: " + object + "}\nproperties: [volume]\n";
  const std::string path = "/tmp/bench_carve_" + object + ".yaml";
  std::ofstream(path) << s;
  const design::Design d = design::LoadDesign(path);
  return design::EvaluateSample(d, design::DefaultPoint(d)).solid;
}

}  // namespace

int main(int argc, char** argv) {
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 3;
  std::ifstream in(std::string(FABATLAS_SOURCE_DIR) + "/configs/designs/cabinet_insert.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  // The uncarved foam block: the carve_swept node as a plain translate.
  std::string uncarved = yaml;
  const std::string node = "    op: carve_swept\n    moving: mug\n    transition: stow\n    offset: 3\n";
  if (uncarved.find(node) == std::string::npos) return std::fprintf(stderr, "cabinet_insert.yaml changed\n"), 1;
  uncarved.replace(uncarved.find(node), node.size(), "    op: translate\n    by: [0, 0, 0]\n");
  const geometry::Solid foam = ObjectOf(uncarved, "foam");
  const geometry::Solid mug = ObjectOf(yaml, "mug");
  // The transition `stow` at the default pocket_floor = 20 (the design's motion).
  swept::RigidMotion stow;
  stow.translation = {swept::Vec3{0, -260, 60}, {0, -80, 60}, {0, 0, 60}, {0, 0, 20}};
  const swept::RigidMotion still;
  geometry::GridSpec g;
  g.voxel_size = 3;
  const design::SourcePlace place{"cabinet_insert.yaml", 0, 0};
  std::printf("cabinet insert: foam %.0f mm^3, mug %.0f mm^3, voxel 3 mm, offset 3 mm\n", foam.Volume(), mug.Volume());
  std::printf(
      "| method | cutter triangles | target triangles | sweep s | subtract s | carve CPU s | carved volume mm^3 |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (bool exact : {true, false}) {
    std::vector<double> sweep, subtract, cpu;
    design::CarveSweptSummary s;
    double volume = 0;
    for (int r = 0; r < repeats; ++r) {
      const double c0 = ProcessCpuSeconds();
      const geometry::Solid carved = design::CarveSwept(foam, mug, stow, still, 3.0, 2, g, place, exact, &s);
      cpu.push_back(ProcessCpuSeconds() - c0);
      sweep.push_back(s.sweep_seconds);
      subtract.push_back(s.subtract_seconds);
      volume = carved.Volume();
    }
    std::printf("| %s | %zu | %zu | %.3f | %.3f | %.3f | %.0f |\n",
                exact ? "exact (CGAL corefinement)" : "level-set difference", s.cutter_triangles, s.target_triangles,
                Median(sweep), Median(subtract), Median(cpu), volume);
  }
  return 0;
}
