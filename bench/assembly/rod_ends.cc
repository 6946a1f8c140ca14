// What each part's mesh puts past the ends of its rods (rod_ends.h), beside
// the library's flags for them: for every rod of a part with a mesh in the
// part library, each end's position and outward direction (part frame) and,
// at 5, 10, 20 and 40 mm past it along the axis, the distance to the mesh
// and how many of 200 rays meet it (from inside). "enclosed" = inside the
// part's body (RodEndProbe::Enclosed): a connector cannot slide off there.
// Usage: assembly_rod_ends [--library configs/assemblies/parts.yaml]
// Prints a Markdown table (docs/assembly.md, "Rod ends against the meshes").
#include <cstdio>
#include <string>

#include "fabatlas/assembly/mass_properties.h"
#include "fabatlas/assembly/part_library.h"
#include "fabatlas/assembly/program.h"
#include "fabatlas/assembly/rod_ends.h"
#include "fabatlas/error.h"

using namespace fabatlas::assembly;

namespace {

std::string Flags(const Primitive& p, bool min_end) {
  if (p.clamped) return "closed (clamped)";
  if (min_end ? p.blocked_min : p.blocked_max) return "closed (blocked)";
  return "open";
}

void PrintEnd(const Part& part, const Primitive& p, const RodEnd& e, bool min_end) {
  std::printf("| %s.%s | %s | %s | (%.1f, %.1f, %.1f) | (%.3f, %.3f, %.3f) |", part.name.c_str(), p.name.c_str(),
              min_end ? "t = 0" : "t = 1", Flags(p, min_end).c_str(), e.position.x(), e.position.y(), e.position.z(),
              e.outward.x(), e.outward.y(), e.outward.z());
  for (const RodEndProbe& q : e.probes)
    std::printf(" %.1f, %d/%d%s |", q.distance_mm, q.hits_from_inside, q.rays_hit, q.Enclosed() ? " enclosed" : "");
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::string library = "configs/assemblies/parts.yaml";
  for (int i = 1; i + 1 < argc; i += 2)
    if (std::string(argv[i]) == "--library") library = argv[i + 1];
  try {
    const PartLibrary lib = LoadPartLibrary(library, DefaultMeshDir());
    std::printf(
        "| part.rod | end | library | end (mm, part frame) | outward | 5 mm past: distance (mm), rays from inside/hit "
        "| 10 mm | 20 mm | 40 mm |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|\n");
    for (const auto& [name, part] : lib.parts) {
      if (part.mesh.empty()) continue;
      bool any = false;
      for (const Primitive& p : part.primitives) any = any || p.type == PrimitiveType::kRod;
      if (!any) continue;
      const PartMesh mesh = ReadPartMesh(DefaultMeshDir() + "/" + part.mesh);
      for (const Primitive& p : part.primitives) {
        if (p.type != PrimitiveType::kRod) continue;
        const RodEnds e = MeasureRodEnds(mesh, p);
        PrintEnd(part, p, e.t0, true);
        PrintEnd(part, p, e.t1, false);
      }
    }
  } catch (const fabatlas::InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return fabatlas::kExitBadInput;
  }
  return 0;
}
