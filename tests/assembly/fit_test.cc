// Primitive frames derived from the part meshes (fit_primitive.h): the fits
// recover what data/fabhacks/EXAMPLES.md states about the same parts, and a
// synthetic wire arc exactly.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "fabatlas/assembly/fit_primitive.h"
#include "fabatlas/assembly/part_library.h"
#include "fabatlas/assembly/program.h"
#include "fabatlas/testing/paths.h"

using namespace fabatlas::assembly;

namespace {

std::string Mesh(const std::string& name) {
  return (fabatlas::testing::SharedDir() / "data/fabhacks/meshes" / name).string();
}

ArcFit Arc(const std::string& mesh, Eigen::Vector3d lo, Eigen::Vector3d hi) {
  return FitArc(MeshPointsIn(Mesh(mesh), lo, hi));
}

const Eigen::Vector3d kBig(1000, 1000, 1000);

}  // namespace

TEST(AssemblyFit, SyntheticWireArc) {
  // A 250° arc of radius 20 around c, normal n, wire radius 2, plus a straight shank.
  const Eigen::Vector3d c(5, -3, 40), n = Eigen::Vector3d(1, 2, 2).normalized();
  const Eigen::Vector3d e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i <= 250; ++i)
    for (int j = 0; j < 12; ++j) {
      const double a = (30 + i) * M_PI / 180, b = j * M_PI / 6;
      const Eigen::Vector3d radial = std::cos(a) * e1 + std::sin(a) * e2;
      p.push_back(c + (20 + 2 * std::cos(b)) * radial + 2 * std::sin(b) * n);
    }
  const ArcFit f = FitArc(p);
  EXPECT_LT((f.centre - c).norm(), 0.3);  // Kåsa on a partial annulus: a small bias
  EXPECT_GT(std::abs(f.normal.dot(n)), 0.9999);
  EXPECT_NEAR(f.radius, 20, 0.1);
  EXPECT_NEAR(f.wire_radius, 2, 0.1);
  EXPECT_NEAR(f.span_deg, 250, 2);
  // The hook frame puts θ = arc/2 at the middle of the wire.
  Primitive hook;
  hook.type = PrimitiveType::kHook;
  hook.shape = {{"arc_radius", 22}, {"arc_angle", 200}, {"thickness", 2}};
  hook.frame = ArcFrame(f, 200);
  const Eigen::Vector3d mid = ConnectorFrame(hook, {100}).translation();
  const Eigen::Vector3d want = c + 20 * (std::cos(155 * M_PI / 180) * e1 + std::sin(155 * M_PI / 180) * e2);
  EXPECT_LT((mid - want).norm(), 0.3);
}

TEST(AssemblyFit, MeshFitsRecoverTheReferenceShapes) {
  // EXAMPLES.md: CeilingHook(25, 300°, 2.5).
  ArcFit f = Arc("ceilinghook.obj", -kBig, Eigen::Vector3d(100, 100, -33));
  EXPECT_NEAR(f.radius, 25, 0.5);
  EXPECT_NEAR(f.wire_radius, 2.5, 0.3);
  EXPECT_NEAR(f.span_deg, 300, 10);
  // Rings XS/S/M/L: arc radius 33.3/43.3/53.3/63.3, thickness 3.3.
  const char* rings[] = {"ringXS.off", "ringS.off", "ringM.off", "ringL.off"};
  for (int k = 0; k < 4; ++k) {
    f = Arc(rings[k], -kBig, kBig);
    EXPECT_NEAR(f.radius, 33.3 + 10 * k, 0.1) << rings[k];
    EXPECT_NEAR(f.wire_radius, 3.3, 0.1) << rings[k];
  }
  // Bird feeder wall hooks (12.5, 180°, 1.25) at y = 16 and 644, z = -61.
  f = Arc("birdfeederenv.obj", -kBig, Eigen::Vector3d(100, 40, -40));
  EXPECT_LT((f.centre - Eigen::Vector3d(0, 16, -61)).norm(), 0.5);
  EXPECT_NEAR(f.radius, 12.5, 0.5);
  EXPECT_NEAR(f.wire_radius, 1.25, 0.1);
  f = Arc("birdfeederenv.obj", Eigen::Vector3d(-100, 620, -100), Eigen::Vector3d(100, 700, -40));
  EXPECT_LT((f.centre - Eigen::Vector3d(0, 644, -61)).norm(), 0.5);
  // Hanger hook 1 (20, 180°, 3.1); bird feeder ring (20, 1.7); eyehook hook
  // (19, thickness 5) and eye (14.82, 4.5); double hook (11.6, 2).
  f = Arc("hanger.off", Eigen::Vector3d(-100, -60, 40), kBig);
  EXPECT_NEAR(f.radius, 20, 0.6);
  EXPECT_NEAR(f.wire_radius, 3.1, 0.2);
  EXPECT_NEAR(f.span_deg, 180, 5);
  f = Arc("birdfeeder.obj", Eigen::Vector3d(-100, -100, 110), kBig);
  EXPECT_NEAR(f.radius, 20, 0.5);
  EXPECT_NEAR(f.wire_radius, 1.7, 0.15);
  f = Arc("hookeyeright.obj", -kBig, Eigen::Vector3d(100, 100, -30));
  EXPECT_NEAR(f.radius, 19, 0.5);
  f = Arc("hookeyeright.obj", Eigen::Vector3d(-100, -100, -22), kBig);
  EXPECT_NEAR(f.radius, 14.82, 0.5);
  EXPECT_NEAR(f.wire_radius, 4.5, 0.2);
  f = Arc("doublehook.off", Eigen::Vector3d(-100, -100, 0), kBig);
  EXPECT_NEAR(f.radius, 11.6, 0.5);
  EXPECT_NEAR(f.wire_radius, 2, 0.1);
  // Hanger bar: Rod(390, 3.5) along y.
  const AxisFit a =
      FitAxis(MeshPointsIn(Mesh("hanger.off"), Eigen::Vector3d(-100, -250, -200), Eigen::Vector3d(100, 250, -104)));
  EXPECT_GT(std::abs(a.axis.y()), 0.999);
  EXPECT_NEAR(a.radius, 3.5, 0.6);
}

TEST(AssemblyFit, HangingLoadRestsInsideTheHookRange) {
  // The lowest point of the ceiling hook (where a hanging load rests) must
  // lie strictly inside θ ∈ [0, 300], not at a bound (where the load would
  // slide off and the solve reports "falls apart"): both for the published
  // frame (PARTS.md) and for the one fitted on ceilinghook.obj.
  const PartLibrary lib =
      LoadPartLibrary((fabatlas::testing::SourceDir() / "configs/assemblies/parts.yaml").string(), DefaultMeshDir());
  Primitive hook = *lib.parts.at("CeilingHook").Find("hook");
  Primitive fitted = hook;
  fitted.frame = ArcFrame(Arc("ceilinghook.obj", -Eigen::Vector3d::Constant(100), Eigen::Vector3d(100, 100, -33)), 300);
  for (const Primitive* h : {&hook, &fitted}) {
    double best = 1e300, best_theta = -1;
    for (double t = 0; t <= 300; t += 1) {
      const double z = ConnectorFrame(*h, {t}).translation().z();
      if (z < best) best = z, best_theta = t;
    }
    EXPECT_GT(best_theta, 20);
    EXPECT_LT(best_theta, 280);
  }
}
