// Folds of an extracted surface (fabatlas/geometry/folded_triangles.h).
#include "fabatlas/geometry/folded_triangles.h"

#include <openvdb/tools/Interpolation.h>

#include <cmath>

#include "solid_impl.h"

namespace fabatlas::geometry {

FoldedTriangles FindFoldedTriangles(const Solid& s, const mesh::TriangleMesh& mesh) {
  FoldedTriangles out;
  if (!s.impl()) return out;
  const openvdb::FloatGrid& grid = *s.impl()->grid;
  const double vs = s.impl()->spec.voxel_size;
  const double iso = kMeshIso * vs;
  auto acc = grid.getConstAccessor();
  const openvdb::tools::GridSampler<openvdb::FloatGrid::ConstAccessor, openvdb::tools::BoxSampler> sampler(
      acc, grid.transform());
  for (const auto& t : mesh.triangles) {
    const auto& a = mesh.vertices[t[0]];
    const auto& b = mesh.vertices[t[1]];
    const auto& c = mesh.vertices[t[2]];
    double centroid[3], e1[3], e2[3];
    for (int k = 0; k < 3; ++k) {
      centroid[k] = (a[k] + b[k] + c[k]) / 3;
      e1[k] = b[k] - a[k];
      e2[k] = c[k] - a[k];
    }
    const double normal[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                              e1[0] * e2[1] - e1[1] * e2[0]};
    // The gradient of the trilinear interpolant of the voxel values in the
    // cell holding the centroid (the cell the surface was extracted from).
    double f[3];
    openvdb::Coord o;
    for (int k = 0; k < 3; ++k) {
      const double x = centroid[k] / vs;
      o[k] = static_cast<int>(std::floor(x));
      f[k] = x - o[k];
    }
    double v[2][2][2];
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j)
        for (int l = 0; l < 2; ++l) v[i][j][l] = acc.getValue(o.offsetBy(i, j, l));
    const auto w = [&f](int k, int side) { return side ? f[k] : 1 - f[k]; };
    double g[3] = {0, 0, 0};
    for (int j = 0; j < 2; ++j)
      for (int l = 0; l < 2; ++l) {
        g[0] += w(1, j) * w(2, l) * (v[1][j][l] - v[0][j][l]);
        g[1] += w(0, j) * w(2, l) * (v[j][1][l] - v[j][0][l]);
        g[2] += w(0, j) * w(1, l) * (v[j][l][1] - v[j][l][0]);
      }
    if (normal[0] * g[0] + normal[1] * g[1] + normal[2] * g[2] >= 0) continue;
    // Facing inward: a fold when the material behind it ends within a voxel
    // (outside again one voxel inward along the gradient).
    const double length = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    if (!(length > 0)) continue;
    const openvdb::Vec3d inward(centroid[0] - g[0] / length * vs, centroid[1] - g[1] / length * vs,
                                centroid[2] - g[2] / length * vs);
    if (sampler.wsSample(inward) <= iso) continue;
    if (out.count == 0) out.first = {centroid[0], centroid[1], centroid[2]};
    ++out.count;
    out.area += 0.5 * std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
  }
  return out;
}

}  // namespace fabatlas::geometry
