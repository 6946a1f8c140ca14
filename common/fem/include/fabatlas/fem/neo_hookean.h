// fabatlas/fem/neo_hookean.h — compressible Neo-Hookean hyperelasticity.
//
// Strain energy density (docs/fem.md; the Cook's membrane
// benchmark material; Fab Forms sandal check), per unit reference volume:
//   Psi(F) = (mu/2) (J^(-2/3) tr C - 3) + (kappa/4) (J^2 - 1 - 2 ln J),
//   C = F^T F, J = det F.
// First Piola-Kirchhoff stress P = dPsi/dF:
//   P = mu J^(-2/3) (F - (tr C / 3) F^-T) + (kappa/2)(J^2 - 1) F^-T
// and its tangent A = dP/dF (analytic). Units: MPa for mu, kappa, Psi and P
// (N/mm^2, i.e. mJ/mm^3). For J <= 0 the energy is +infinity.
//
// Matrices are row-major 3x3 arrays: F[i][J] = dx_i/dX_J. The tangent is a 9x9
// row-major array with A[3*i+J][3*k+L] = dP_iJ / dF_kL.
#pragma once

#include <array>

#include "fabatlas/vec3.h"

namespace fabatlas::fem {

using Mat3 = std::array<Vec3, 3>;
using Tangent9 = std::array<std::array<double, 9>, 9>;

struct Material {
  double mu = 0.0;     // shear modulus, MPa (> 0)
  double kappa = 0.0;  // bulk modulus, MPa (> 0)

  // Small-strain equivalents: mu = E/(2(1+nu)), kappa = E/(3(1-2nu)).
  // Throws InputError unless E > 0 and -1 < nu < 0.5.
  static Material FromYoungPoisson(double youngs_modulus_mpa, double poisson_ratio);
  // kappa = 2 mu (1+nu) / (3 (1-2nu)), as in the Cook's membrane benchmark.
  static Material FromShearPoisson(double mu_mpa, double poisson_ratio);
};

// Energy density Psi(F), MPa; +infinity if det F <= 0.
double NeoHookeanEnergy(const Material& m, const Mat3& F);
// First Piola-Kirchhoff stress P(F), MPa. Requires det F > 0.
Mat3 NeoHookeanStress(const Material& m, const Mat3& F);
// Material tangent dP/dF (9x9, layout above). Requires det F > 0.
Tangent9 NeoHookeanTangent(const Material& m, const Mat3& F);

}  // namespace fabatlas::fem
