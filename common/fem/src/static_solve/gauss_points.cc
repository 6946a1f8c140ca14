// Gauss points and deformation gradients (static_solve/gauss_points.h).
#include "gauss_points.h"

#include <string>

#include <Eigen/Dense>

#include "fabatlas/error.h"

namespace fabatlas::fem::internal {

std::vector<GaussPoint> PrecomputeGaussPoints(const HexMesh& mesh) {
  std::vector<GaussPoint> gps(mesh.elements.size() * 8);
  for (std::size_t e = 0; e < mesh.elements.size(); ++e) {
    const auto& el = mesh.elements[e];
    Eigen::Matrix3d Jc = Eigen::Matrix3d::Zero();  // dX/dxi at the centre
    for (int a = 0; a < 8; ++a)
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) Jc(i, j) += 0.125 * mesh.nodes[el[a]][i] * kNodeSign[a][j];
    const double j0 = Jc.determinant();
    const Eigen::Matrix3d Jc_inv = j0 > 0 ? Eigen::Matrix3d(Jc.inverse()) : Eigen::Matrix3d::Zero();
    for (int g = 0; g < 8; ++g) {
      const double xi[3] = {kNodeSign[g][0] * kGauss, kNodeSign[g][1] * kGauss, kNodeSign[g][2] * kGauss};
      double dNdxi[8][3];
      for (int a = 0; a < 8; ++a) {
        const double s[3] = {1 + kNodeSign[a][0] * xi[0], 1 + kNodeSign[a][1] * xi[1], 1 + kNodeSign[a][2] * xi[2]};
        dNdxi[a][0] = 0.125 * kNodeSign[a][0] * s[1] * s[2];
        dNdxi[a][1] = 0.125 * kNodeSign[a][1] * s[0] * s[2];
        dNdxi[a][2] = 0.125 * kNodeSign[a][2] * s[0] * s[1];
      }
      Eigen::Matrix3d J0 = Eigen::Matrix3d::Zero();  // dX_i/dxi_j
      for (int a = 0; a < 8; ++a)
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) J0(i, j) += mesh.nodes[el[a]][i] * dNdxi[a][j];
      const double det = J0.determinant();
      if (!(det > 0)) {
        throw InputError("hex mesh: element " + std::to_string(e) +
                         " is inverted or degenerate (det J = " + std::to_string(det) + "); check the node order");
      }
      const Eigen::Matrix3d Jinv = J0.inverse();
      GaussPoint& gp = gps[e * 8 + g];
      gp.weight = det;  // Gauss weights are 1
      for (int a = 0; a < 8; ++a)
        for (int j = 0; j < 3; ++j) {
          gp.dN[a][j] = dNdxi[a][0] * Jinv(0, j) + dNdxi[a][1] * Jinv(1, j) + dNdxi[a][2] * Jinv(2, j);
        }
      // d phi_k / d xi_m = -2 xi_k delta_km.
      for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 3; ++j) gp.G[k][j] = (j0 / det) * (-2.0 * xi[k]) * Jc_inv(k, j);
    }
  }
  return gps;
}

}  // namespace fabatlas::fem::internal
