// The area of a triangle mesh's surface (see surface_area.h).
#include "fabatlas/mesh/surface_area.h"

#include <cmath>

#include "triangles_about.h"

namespace fabatlas::mesh {

double SurfaceArea(const TriangleMesh& mesh, const std::array<double, 3>& origin) {
  double area2 = 0.0;
  ForEachTriangleAbout(mesh, origin, [&](const std::array<std::array<double, 3>, 3>& p) {
    const double u[3] = {p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]};
    const double w[3] = {p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]};
    const double nx = u[1] * w[2] - u[2] * w[1], ny = u[2] * w[0] - u[0] * w[2], nz = u[0] * w[1] - u[1] * w[0];
    area2 += std::sqrt(nx * nx + ny * ny + nz * nz);
  });
  return area2 / 2.0;
}

}  // namespace fabatlas::mesh
