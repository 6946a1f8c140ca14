// Thin bending against closed-form and published answers, at 1, 2 and 4
// hexahedra through the thickness (voxel FEM on real parts has 1-3): the
// large-deflection elastica of a tip-loaded cantilever and the clamped square
// plate under uniform pressure. Full-integration Q1 locks here; the
// incompatible-mode element (the default, docs/fem.md) must not.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "fabatlas/fem/hex_mesh.h"
#include "fabatlas/fem/static_solve.h"
#include "cantilever.h"
#include "elastica.h"

namespace fabatlas::fem {
namespace {

using Element = StaticSolveOptions::Element;

// Our elastica integration against the published elliptic-integral table
// (Mattiasson 1981, Table 1): alpha = 1: v/L = 0.30172, u/L = 0.05643;
// alpha = 3: v/L = 0.60325, u/L = 0.25442.
TEST(FemBendingReference, ElasticaMatchesMattiasson) {
  const Elastica a1 = ElasticaTip(1.0), a3 = ElasticaTip(3.0);
  EXPECT_NEAR(a1.v, 0.30172, 2e-5);
  EXPECT_NEAR(a1.u, 0.05643, 2e-5);
  EXPECT_NEAR(a3.v, 0.60325, 2e-5);
  EXPECT_NEAR(a3.u, 0.25442, 2e-5);
}

// Cantilever L = 200 mm, 4 x 4 mm section, E = 1000 MPa, nu = 0, dead tip
// traction P = alpha E I / L^2 on the end face, clamped end face; voxel
// hexahedra of 4 / 2 / 1 mm (1 / 2 / 4 through the thickness). Returns the
// mean vertical tip displacement over the end-face nodes, mm.
double CantileverTip(double voxel, double alpha, Element element) {
  const double L = 200, h = 4, E = 1000;
  const Cantilever c = MakeCantilever(L, h, voxel, alpha * E * (h * h * h * h / 12) / (L * L));
  StaticSolveOptions o;
  o.element = element;
  const StaticSolveSummary r = SolveStatic(c.mesh, Material::FromYoungPoisson(E, 0.0), c.bc, o);
  EXPECT_TRUE(r.converged) << r.message;
  return c.TipDeflection(r);
}

struct Through {
  double voxel;
  int layers;
  double tolerance;  // relative, against the reference
};

class FemCantileverElastica : public ::testing::TestWithParam<Through> {};

TEST_P(FemCantileverElastica, IncompatibleModesMatchTheElastica) {
  const double reference = 200 * ElasticaTip(1.0).v;  // 60.34 mm
  const double tip = CantileverTip(GetParam().voxel, 1.0, Element::kIncompatibleModes);
  RecordProperty("tip", std::to_string(tip));
  EXPECT_NEAR(tip, reference, GetParam().tolerance * reference) << GetParam().layers << " through the thickness";
}

INSTANTIATE_TEST_SUITE_P(ElementsThroughThickness, FemCantileverElastica,
                         ::testing::Values(Through{4.0, 1, 0.02}, Through{2.0, 2, 0.02}, Through{1.0, 4, 0.02}),
                         [](const auto& info) { return "layers" + std::to_string(info.param.layers); });

// Q1 on the same 2-layer mesh locks: much too stiff (the failure the
// incompatible modes remove).
TEST(FemCantileverElastica, Q1LocksWithTwoLayers) {
  const double reference = 200 * ElasticaTip(1.0).v;
  const double tip = CantileverTip(2.0, 1.0, Element::kQ1);
  RecordProperty("tip_q1", std::to_string(tip));
  EXPECT_LT(tip, 0.95 * reference);
}

// Clamped square plate, side a = 100 mm, thickness t = 1 mm (a/t = 100),
// E = 1000 MPa, nu = 0.3, uniform dead pressure q: Kirchhoff theory gives the
// centre deflection w = 0.00126532 q a^4 / D, D = E t^3 / (12 (1 - nu^2))
// (Timoshenko & Woinowsky-Krieger 1959, Table 35: 0.00126; Taylor &
// Govindjee 2004: 0.00126532); the transverse-shear correction at a/t = 100
// is below 0.3%. One quarter (x, y in [0, 50]) with symmetry planes at
// x = 50 and y = 50, n x n elements in plane, `layers` through t; q is small
// (w ~ t/100) so the response is linear.
double ClampedPlateCentre(int n, int layers, Element element, double* reference) {
  const double a = 100, t = 1, E = 1000, nu = 0.3;
  const double D = E * t * t * t / (12 * (1 - nu * nu));
  const double q = 0.01 * t * D / (0.00126532 * a * a * a * a);
  *reference = 0.00126532 * q * a * a * a * a / D;
  const HexMesh mesh =
      HexMeshFromQuadPatch({Vec2{0, 0}, Vec2{a / 2, 0}, Vec2{a / 2, a / 2}, Vec2{0, a / 2}}, n, n, t, layers);
  auto id = [n](int i, int j, int k) { return i + (n + 1) * (j + (n + 1) * k); };
  BoundaryConditions bc;
  for (int k = 0; k <= layers; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        if (i == 0 || j == 0) {
          bc.FixNode(id(i, j, k));
          continue;
        }
        if (i == n) bc.dirichlet.push_back({id(i, j, k), 0, 0.0});
        if (j == n) bc.dirichlet.push_back({id(i, j, k), 1, 0.0});
      }
  FaceTraction pressure;
  pressure.total_force = {0, 0, -q * (a / 2) * (a / 2)};
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      pressure.faces.push_back(
          {id(i, j, layers), id(i + 1, j, layers), id(i + 1, j + 1, layers), id(i, j + 1, layers)});
  bc.tractions.push_back(pressure);
  StaticSolveOptions o;
  o.element = element;
  const StaticSolveSummary r = SolveStatic(mesh, Material::FromYoungPoisson(E, nu), bc, o);
  EXPECT_TRUE(r.converged) << r.message;
  return -0.5 * (r.displacements[id(n, n, 0)][2] + r.displacements[id(n, n, layers)][2]);
}

class FemClampedPlate : public ::testing::TestWithParam<Through> {};

TEST_P(FemClampedPlate, IncompatibleModesMatchKirchhoff) {
  double reference = 0;
  const double w = ClampedPlateCentre(20, GetParam().layers, Element::kIncompatibleModes, &reference);
  RecordProperty("w", std::to_string(w));
  EXPECT_NEAR(w, reference, GetParam().tolerance * reference) << GetParam().layers << " through the thickness";
}

INSTANTIATE_TEST_SUITE_P(ElementsThroughThickness, FemClampedPlate,
                         ::testing::Values(Through{0, 1, 0.02}, Through{0, 2, 0.02}, Through{0, 4, 0.02}),
                         [](const auto& info) { return "layers" + std::to_string(info.param.layers); });

TEST(FemClampedPlate, Q1LocksWithTwoLayers) {
  double reference = 0;
  const double w = ClampedPlateCentre(20, 2, Element::kQ1, &reference);
  RecordProperty("w_q1", std::to_string(w));
  EXPECT_LT(w, 0.5 * reference);
}

}  // namespace
}  // namespace fabatlas::fem
