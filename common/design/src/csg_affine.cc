// Affine maps of OpenSCAD's CSG tree (csg_affine.h).
#include "csg_affine.h"

#include <cmath>
#include <vector>

#include "csg_arguments.h"
#include "fabatlas/scad/customizer.h"

namespace fabatlas::design::csg {

Affine Compose(const Affine& a, const Affine& b) {  // a after b
  Affine c{};
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) c[4 * r + k] = a[4 * r] * b[k] + a[4 * r + 1] * b[4 + k] + a[4 * r + 2] * b[8 + k];
    c[4 * r + 3] = a[4 * r] * b[3] + a[4 * r + 1] * b[7] + a[4 * r + 2] * b[11] + a[4 * r + 3];
  }
  return c;
}

std::string AffineText(const Affine& a) {
  std::string s;
  for (double v : a) s += scad::FormatScadNumber(v) + ",";
  return s;
}

void Transform(mesh::TriangleMesh& m, const Affine& a) {
  for (auto& v : m.vertices) {
    const double x = v[0], y = v[1], z = v[2];
    v = {a[0] * x + a[1] * y + a[2] * z + a[3], a[4] * x + a[5] * y + a[6] * z + a[7],
         a[8] * x + a[9] * y + a[10] * z + a[11]};
  }
}

Affine MatrixOf(const CsgNode& n) {
  Affine a = kIdentity;
  auto it = n.args.find("m");  // OpenSCAD writes the matrix as the first positional argument
  const CsgValue* matrix = it != n.args.end() ? &it->second : n.positional.empty() ? nullptr : &n.positional[0];
  if (!matrix || matrix->items.size() < 3) throw NoNativeEquivalent{"multmatrix without a 4x4 matrix"};
  for (int r = 0; r < 3; ++r) {
    std::vector<double> row = Numbers(matrix->items[r]);
    if (row.size() < 4) throw NoNativeEquivalent{"multmatrix with a short row"};
    for (int k = 0; k < 4; ++k) a[4 * r + k] = row[k];
  }
  // A last row (0, 0, 0, w) scales by 1/w, as OpenSCAD applies the matrix
  // to homogeneous points; any other last row is a projection.
  if (matrix->items.size() >= 4) {
    const std::vector<double> w = Numbers(matrix->items[3]);
    if (w.size() >= 4 && (w[0] != 0 || w[1] != 0 || w[2] != 0 || w[3] == 0))
      throw NoNativeEquivalent{"multmatrix with a projective last row"};
    if (w.size() >= 4 && w[3] != 1)
      for (double& x : a) x /= w[3];
  }
  return a;
}

double SimilarityScale(const Affine& a) {
  const double c[3][3] = {{a[0], a[1], a[2]}, {a[4], a[5], a[6]}, {a[8], a[9], a[10]}};
  double g[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) g[i][j] = c[0][i] * c[0][j] + c[1][i] * c[1][j] + c[2][i] * c[2][j];
  const double s2 = (g[0][0] + g[1][1] + g[2][2]) / 3;
  if (!(s2 > 0)) return 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (std::abs(g[i][j] - (i == j ? s2 : 0)) > 1e-9 * s2) return 0;
  return std::sqrt(s2);
}

}  // namespace fabatlas::design::csg
