// Prints the primitive fit of a region of a part mesh (the derivation behind
// `fit:` in configs/assemblies/parts.yaml). Usage:
//   assembly_fit_frames MESH arc|axis XMIN YMIN ZMIN XMAX YMAX ZMAX [ARC_ANGLE]
#include <cstdio>
#include <cstdlib>
#include <string>

#include "fabatlas/assembly/fit_primitive.h"
#include "fabatlas/error.h"

using namespace fabatlas::assembly;

int main(int argc, char** argv) {
  if (argc < 9) {
    std::fprintf(stderr, "usage: %s MESH arc|axis XMIN YMIN ZMIN XMAX YMAX ZMAX [ARC_ANGLE]\n", argv[0]);
    return fabatlas::kExitBadInput;
  }
  try {
    const Eigen::Vector3d lo(std::atof(argv[3]), std::atof(argv[4]), std::atof(argv[5]));
    const Eigen::Vector3d hi(std::atof(argv[6]), std::atof(argv[7]), std::atof(argv[8]));
    const auto points = MeshPointsIn(argv[1], lo, hi);
    if (std::string(argv[2]) == "arc") {
      const ArcFit f = FitArc(points);
      const double arc = argc > 9 ? std::atof(argv[9]) : 360;
      const Frame fr = ArcFrame(f, arc);
      std::printf("points %d centre [%.2f, %.2f, %.2f] normal [%.3f, %.3f, %.3f] radius %.2f wire %.2f span %.1f\n",
                  f.points, f.centre.x(), f.centre.y(), f.centre.z(), f.normal.x(), f.normal.y(), f.normal.z(),
                  f.radius, f.wire_radius, f.span_deg);
      std::printf("frame [[%.2f, %.2f, %.2f], [%.1f, %.1f, %.1f]]\n", fr.position.x(), fr.position.y(), fr.position.z(),
                  fr.euler_deg.x(), fr.euler_deg.y(), fr.euler_deg.z());
    } else {
      const AxisFit f = FitAxis(points);
      const Frame fr = AxisFrame(f);
      std::printf("points %d centre [%.2f, %.2f, %.2f] axis [%.3f, %.3f, %.3f] length %.2f radius %.2f\n", f.points,
                  f.centre.x(), f.centre.y(), f.centre.z(), f.axis.x(), f.axis.y(), f.axis.z(), f.length, f.radius);
      std::printf("frame [[%.2f, %.2f, %.2f], [%.1f, %.1f, %.1f]]\n", fr.position.x(), fr.position.y(), fr.position.z(),
                  fr.euler_deg.x(), fr.euler_deg.y(), fr.euler_deg.z());
    }
  } catch (const fabatlas::InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return fabatlas::kExitBadInput;
  }
  return 0;
}
