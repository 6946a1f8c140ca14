// static_solve/gauss_points.h (internal to fabatlas_fem) — the reference
// data of the hexahedra's Gauss points and the deformation gradient there.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "fabatlas/fem/hex_mesh.h"
#include "fabatlas/fem/neo_hookean.h"

namespace fabatlas::fem::internal {

constexpr double kGauss = 0.57735026918962576451;  // 1/sqrt(3)
constexpr int kNodeSign[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                 {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};

// Reference-configuration data of one Gauss point: dN_a/dX, weight*det J, and
// the gradients G_k = dphi_k/dX of the three incompatible modes
// phi_k = 1 - xi_k^2 (Wilson, Taylor, Doherty & Ghaboussi 1973), taken as
// Simo & Armero 1992, Eq. (4.9) do: G_k = (j0/j) J0^-T grad_xi phi_k with the
// Jacobian J0 = dX/dxi at the element centre, so that int G_k dV = 0 (the
// patch test) on any hexahedron.
struct GaussPoint {
  double dN[8][3];
  double G[3][3];  // G[k][J] = d phi_k / d X_J (scaled as above)
  double weight;
};

// Full 2x2x2 Gauss integration of the trilinear hexahedron: 8 points per
// element, element by element. Throws InputError for an inverted or
// degenerate element.
std::vector<GaussPoint> PrecomputeGaussPoints(const HexMesh& mesh);

// F = I + sum_a u_a (x) dN_a + sum_k alpha_k (x) G_k. `alpha` points at the
// element's 9 incompatible-mode amplitudes (alpha[3k + i]: component i of
// mode k, mm), or is null for plain Q1.
// (Inline: the element loops call it at every Gauss point.)
inline Mat3 DeformationGradient(const GaussPoint& gp, const std::array<int, 8>& el, const Eigen::VectorXd& u,
                                const double* alpha) {
  Mat3 F{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  for (int a = 0; a < 8; ++a) {
    const double* ua = u.data() + 3 * static_cast<std::size_t>(el[a]);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) F[i][j] += ua[i] * gp.dN[a][j];
  }
  if (alpha) {
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) F[i][j] += alpha[3 * k + i] * gp.G[k][j];
  }
  return F;
}

}  // namespace fabatlas::fem::internal
