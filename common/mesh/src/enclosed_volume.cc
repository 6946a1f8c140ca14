// The enclosed volume of a triangle mesh (see enclosed_volume.h).
#include "fabatlas/mesh/enclosed_volume.h"

#include "triangles_about.h"

namespace fabatlas::mesh {

double EnclosedVolume(const TriangleMesh& mesh, const std::array<double, 3>& origin) {
  double volume6 = 0.0;
  ForEachTriangleAbout(mesh, origin, [&](const std::array<std::array<double, 3>, 3>& p) {
    // p0 . (p1 x p2)
    const double cx = p[1][1] * p[2][2] - p[1][2] * p[2][1];
    const double cy = p[1][2] * p[2][0] - p[1][0] * p[2][2];
    const double cz = p[1][0] * p[2][1] - p[1][1] * p[2][0];
    volume6 += p[0][0] * cx + p[0][1] * cy + p[0][2] * cz;
  });
  return volume6 / 6.0;
}

}  // namespace fabatlas::mesh
