// The Neo-Hookean energy of docs/fem.md (the deal.II program of docs/references.md): stress and tangent against
// central finite differences, and the small-strain limit against linear
// elasticity (Hooke's law with lambda = kappa - 2mu/3).
#include "fabatlas/fem/neo_hookean.h"

#include <gtest/gtest.h>

#include <cmath>

#include "fabatlas/error.h"

namespace fabatlas::fem {
namespace {

const Material kMat = Material::FromShearPoisson(0.4225, 0.3);

// A general deformation gradient with det F > 0 (rotation + stretch + shear).
Mat3 SampleF() { return Mat3{{{1.10, 0.23, -0.07}, {-0.12, 0.91, 0.15}, {0.05, -0.09, 1.22}}}; }

TEST(FemNeoHookean, ZeroEnergyAndStressInReferenceState) {
  const Mat3 I{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  EXPECT_NEAR(NeoHookeanEnergy(kMat, I), 0.0, 1e-15);
  const Mat3 P = NeoHookeanStress(kMat, I);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(P[i][j], 0.0, 1e-15);
}

TEST(FemNeoHookean, InvertedElementHasInfiniteEnergy) {
  const Mat3 F{{{-1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  EXPECT_TRUE(std::isinf(NeoHookeanEnergy(kMat, F)));
}

TEST(FemNeoHookean, StressIsEnergyGradient) {
  const Mat3 F = SampleF();
  const Mat3 P = NeoHookeanStress(kMat, F);
  const double h = 1e-6;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      Mat3 Fp = F, Fm = F;
      Fp[i][j] += h;
      Fm[i][j] -= h;
      const double fd = (NeoHookeanEnergy(kMat, Fp) - NeoHookeanEnergy(kMat, Fm)) / (2 * h);
      EXPECT_NEAR(P[i][j], fd, 1e-7 + 1e-6 * std::abs(fd)) << "P[" << i << "][" << j << "]";
    }
}

TEST(FemNeoHookean, TangentIsStressGradient) {
  const Mat3 F = SampleF();
  const Tangent9 A = NeoHookeanTangent(kMat, F);
  const double h = 1e-6;
  double max_err = 0, max_val = 0;
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < 3; ++l) {
      Mat3 Fp = F, Fm = F;
      Fp[k][l] += h;
      Fm[k][l] -= h;
      const Mat3 Pp = NeoHookeanStress(kMat, Fp), Pm = NeoHookeanStress(kMat, Fm);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const double fd = (Pp[i][j] - Pm[i][j]) / (2 * h);
          max_err = std::max(max_err, std::abs(A[3 * i + j][3 * k + l] - fd));
          max_val = std::max(max_val, std::abs(fd));
        }
    }
  EXPECT_LT(max_err, 1e-7 * max_val) << "max |A - FD| = " << max_err;
  // Hyperelastic tangent has major symmetry A_iJkL = A_kLiJ.
  for (int r = 0; r < 9; ++r)
    for (int c = 0; c < 9; ++c) EXPECT_NEAR(A[r][c], A[c][r], 1e-12 * max_val);
}

TEST(FemNeoHookean, SmallStrainLimitIsHookesLaw) {
  const Material m = Material::FromYoungPoisson(200.0, 0.3);
  const double lambda = m.kappa - 2.0 * m.mu / 3.0;
  // Symmetric small strain eps; F = I + eps.
  const double eps[3][3] = {{1e-6, 2e-7, 0}, {2e-7, -3e-7, 5e-7}, {0, 5e-7, 4e-7}};
  Mat3 F{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) F[i][j] = (i == j ? 1.0 : 0.0) + eps[i][j];
  const Mat3 P = NeoHookeanStress(m, F);
  const double tr = eps[0][0] + eps[1][1] + eps[2][2];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double hooke = lambda * tr * (i == j ? 1 : 0) + 2 * m.mu * eps[i][j];
      EXPECT_NEAR(P[i][j], hooke, 1e-3 * 200.0 * 1e-6) << i << j;
    }
}

TEST(FemNeoHookean, MaterialConstants) {
  const Material a = Material::FromYoungPoisson(1000.0, 0.25);
  EXPECT_DOUBLE_EQ(a.mu, 400.0);
  EXPECT_NEAR(a.kappa, 1000.0 / 1.5, 1e-12);
  // Cook's membrane: kappa = 2 mu (1+nu) / (3 (1-2nu)).
  const Material c = Material::FromShearPoisson(0.4225, 0.3);
  EXPECT_NEAR(c.kappa, 2 * 0.4225 * 1.3 / (3 * 0.4), 1e-15);
  EXPECT_THROW(Material::FromYoungPoisson(-1.0, 0.3), InputError);
  EXPECT_THROW(Material::FromYoungPoisson(10.0, 0.5), InputError);
}

}  // namespace
}  // namespace fabatlas::fem
