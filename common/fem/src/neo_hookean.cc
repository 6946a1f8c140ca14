#include "fabatlas/fem/neo_hookean.h"

#include <cmath>
#include <limits>
#include <string>

#include "fabatlas/error.h"

namespace fabatlas::fem {
namespace {

double Det(const Mat3& F) {
  return F[0][0] * (F[1][1] * F[2][2] - F[1][2] * F[2][1]) - F[0][1] * (F[1][0] * F[2][2] - F[1][2] * F[2][0]) +
         F[0][2] * (F[1][0] * F[2][1] - F[1][1] * F[2][0]);
}

// F^-T = cofactor(F) / det F.
Mat3 InverseTranspose(const Mat3& F, double J) {
  Mat3 H;
  H[0][0] = (F[1][1] * F[2][2] - F[1][2] * F[2][1]) / J;
  H[0][1] = (F[1][2] * F[2][0] - F[1][0] * F[2][2]) / J;
  H[0][2] = (F[1][0] * F[2][1] - F[1][1] * F[2][0]) / J;
  H[1][0] = (F[0][2] * F[2][1] - F[0][1] * F[2][2]) / J;
  H[1][1] = (F[0][0] * F[2][2] - F[0][2] * F[2][0]) / J;
  H[1][2] = (F[0][1] * F[2][0] - F[0][0] * F[2][1]) / J;
  H[2][0] = (F[0][1] * F[1][2] - F[0][2] * F[1][1]) / J;
  H[2][1] = (F[0][2] * F[1][0] - F[0][0] * F[1][2]) / J;
  H[2][2] = (F[0][0] * F[1][1] - F[0][1] * F[1][0]) / J;
  return H;
}

double TraceC(const Mat3& F) {
  double s = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s += F[i][j] * F[i][j];
  return s;
}

}  // namespace

Material Material::FromYoungPoisson(double E, double nu) {
  if (!(E > 0) || !(nu > -1.0 && nu < 0.5)) {
    throw InputError("material: need E > 0 and -1 < nu < 0.5, got E=" + std::to_string(E) +
                     " nu=" + std::to_string(nu));
  }
  return Material{E / (2 * (1 + nu)), E / (3 * (1 - 2 * nu))};
}

Material Material::FromShearPoisson(double mu, double nu) {
  if (!(mu > 0) || !(nu > -1.0 && nu < 0.5)) {
    throw InputError("material: need mu > 0 and -1 < nu < 0.5, got mu=" + std::to_string(mu) +
                     " nu=" + std::to_string(nu));
  }
  return Material{mu, 2 * mu * (1 + nu) / (3 * (1 - 2 * nu))};
}

double NeoHookeanEnergy(const Material& m, const Mat3& F) {
  const double J = Det(F);
  if (!(J > 0)) return std::numeric_limits<double>::infinity();
  return 0.5 * m.mu * (std::pow(J, -2.0 / 3.0) * TraceC(F) - 3.0) + 0.25 * m.kappa * (J * J - 1.0 - 2.0 * std::log(J));
}

Mat3 NeoHookeanStress(const Material& m, const Mat3& F) {
  const double J = Det(F);
  const Mat3 H = InverseTranspose(F, J);
  const double a = m.mu * std::pow(J, -2.0 / 3.0);
  const double I1 = TraceC(F);
  const double b = 0.5 * m.kappa * (J * J - 1.0);
  Mat3 P;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) P[i][j] = a * (F[i][j] - I1 / 3.0 * H[i][j]) + b * H[i][j];
  return P;
}

Tangent9 NeoHookeanTangent(const Material& m, const Mat3& F) {
  // Differentiating P with dH_iJ/dF_kL = -H_iL H_kJ, dJ/dF = J H,
  // d(J^-2/3)/dF = -2/3 J^-2/3 H, d(tr C)/dF = 2F:
  //  A = a [ d_ik d_JL - 2/3 F_iJ H_kL - 2/3 H_iJ F_kL + 2/9 I1 H_iJ H_kL
  //          + I1/3 H_iL H_kJ ]
  //    + kappa J^2 H_iJ H_kL - (kappa/2)(J^2 - 1) H_iL H_kJ,   a = mu J^-2/3.
  const double J = Det(F);
  const Mat3 H = InverseTranspose(F, J);
  const double a = m.mu * std::pow(J, -2.0 / 3.0);
  const double I1 = TraceC(F);
  const double kJ2 = m.kappa * J * J;
  const double b = 0.5 * m.kappa * (J * J - 1.0);
  Tangent9 A;
  for (int i = 0; i < 3; ++i)
    for (int jj = 0; jj < 3; ++jj)
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) {
          double v =
              a * ((i == k && jj == l ? 1.0 : 0.0) - 2.0 / 3.0 * F[i][jj] * H[k][l] - 2.0 / 3.0 * H[i][jj] * F[k][l] +
                   2.0 / 9.0 * I1 * H[i][jj] * H[k][l] + I1 / 3.0 * H[i][l] * H[k][jj]);
          v += kJ2 * H[i][jj] * H[k][l] - b * H[i][l] * H[k][jj];
          A[3 * i + jj][3 * k + l] = v;
        }
  return A;
}

}  // namespace fabatlas::fem
