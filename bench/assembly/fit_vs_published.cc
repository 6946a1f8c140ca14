// How far primitive frames fitted from part meshes (FitArc / FitAxis, the
// `fit:` of a part library, for user parts without annotations) are from the
// frames the FabHacks implementation publishes for the same parts
// (configs/assemblies/parts.yaml, data/fabhacks/PARTS.md). Each row fits the
// mesh vertices inside a box around one primitive and compares:
//   hook / ring: arc centre (the primitive frame's origin) distance, angle
//     between the fitted plane normal and the published arc axis (frame x),
//     centre-arc radius and wire radius against arc_radius and thickness;
//   rod: distance of the published centre from the fitted axis, offset along
//     it, angle between the axes, radius.
// Usage: assembly_fit_vs_published [--library configs/assemblies/parts.yaml]
// Prints a Markdown table (docs/assembly-notes.md, "Fitted against published frames").
#include <cmath>
#include <cstdio>
#include <string>

#include "fabatlas/assembly/fit_primitive.h"
#include "fabatlas/assembly/part_library.h"
#include "fabatlas/assembly/program.h"
#include "fabatlas/error.h"

using namespace fabatlas::assembly;

namespace {

struct Row {
  const char* part;  // in the library
  const char* primitive;
  Eigen::Vector3d lo, hi;  // selection box, mesh frame (mm)
};

double AxisAngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::min(1.0, std::abs(a.normalized().dot(b.normalized())))) * 180 / M_PI;
}

}  // namespace

int main(int argc, char** argv) {
  std::string library = "configs/assemblies/parts.yaml";
  for (int i = 1; i + 1 < argc; i += 2)
    if (std::string(argv[i]) == "--library") library = argv[i + 1];
  const double B = 100;
  // The selection boxes are the ones the part library used before the
  // published frames were available (one box per primitive, around it).
  const Row rows[] = {
      {"CeilingHook", "hook", {-B, -B, -B}, {B, B, -33}},
      {"BirdFeederEnv", "hook1", {-B, -B, -B}, {B, 40, -40}},
      {"BirdFeederEnv", "hook2", {-B, 620, -B}, {B, 700, -40}},
      {"HookEyeRight", "hook", {-B, -B, -B}, {B, B, -30}},
      {"HookEyeRight", "ring", {-B, -B, -22}, {B, B, B}},
      {"Hanger", "hook1", {-B, -60, 40}, {B, 60, 200}},
      {"Hanger", "rod", {-B, -250, -200}, {B, 250, -104}},
      {"Hanger", "hook2", {-B, 150, -200}, {B, 250, -60}},
      {"Hanger", "hook3", {-B, -250, -200}, {B, -150, -60}},
      {"BirdFeeder", "ring", {-B, -B, 110}, {B, B, 200}},
      {"FabricHanger", "hook1", {-B, -B, 55}, {B, B, 200}},
      {"FabricHanger", "rod", {-300, -B, -200}, {300, B, -85}},
      {"Turnbuckle40", "hook1", {-B, 57, -B}, {B, B, B}},
      {"Turnbuckle40", "hook2", {-B, -B, -B}, {B, -57, B}},
  };
  try {
    const PartLibrary lib = LoadPartLibrary(library, DefaultMeshDir());
    std::printf(
        "| part.primitive | mesh | fitted points | centre distance (mm) | axis angle (deg) | radius fit / published "
        "(mm) | wire or rod radius fit / published (mm) |\n");
    std::printf("|---|---|---|---|---|---|---|\n");
    for (const Row& r : rows) {
      const Part& part = lib.parts.at(r.part);
      const Primitive& p = *part.Find(r.primitive);
      const auto points = MeshPointsIn(DefaultMeshDir() + "/" + part.mesh, r.lo, r.hi);
      const Eigen::Isometry3d b = ToIsometry(p.frame);
      if (p.type == PrimitiveType::kRod) {
        const AxisFit f = FitAxis(points);
        const Eigen::Vector3d d = b.translation() - f.centre;
        const double along = d.dot(f.axis), across = (d - along * f.axis).norm();
        std::printf("| %s.%s | %s | %d | %.2f across, %.2f along | %.2f | length %.1f / %.1f | %.2f / %.2f |\n", r.part,
                    r.primitive, part.mesh.c_str(), f.points, across, along, AxisAngleDeg(f.axis, b.linear().col(2)),
                    f.length, p.Shape("length"), f.radius, p.Shape("radius"));
      } else {
        const ArcFit f = FitArc(points);
        std::printf("| %s.%s | %s | %d | %.2f | %.2f | %.2f / %.2f | %.2f / %.2f |\n", r.part, r.primitive,
                    part.mesh.c_str(), f.points, (f.centre - b.translation()).norm(),
                    AxisAngleDeg(f.normal, b.linear().col(0)), f.radius, p.Shape("arc_radius"), f.wire_radius,
                    p.Shape("thickness"));
      }
    }
  } catch (const fabatlas::InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return fabatlas::kExitBadInput;
  }
  return 0;
}
