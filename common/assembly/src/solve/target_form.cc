// The target as the solve compares it (solve/target_form.h).
#include "target_form.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace fabatlas::assembly::internal {

TargetForm TargetForm::Of(const Program& prog) {
  TargetForm f;
  f.offset = prog.TargetOffset();
  f.t = prog.target_frame.position;
  f.r = EulerToRotation(prog.target_frame.euler_deg);
  switch (prog.TargetPrimitive().type) {
    case PrimitiveType::kRing:
      f.ignore = 0;
      break;
    case PrimitiveType::kTube:
      f.ignore = 1;
      break;
    case PrimitiveType::kRod:
    case PrimitiveType::kHemisphere:
      f.ignore = 2;
      break;
    case PrimitiveType::kClip:
    case PrimitiveType::kSurface:
      f.has_twin = true;
      f.twin = EulerToRotation(Eigen::Vector3d(0, 0, 180)) * f.r;
      break;
    default:
      break;
  }
  // Euler angles of the target (PARTS.md: b = −asin R31, a = atan2(R32, R33), c = atan2(R21, R11)).
  const double a = std::atan2(f.r(2, 1), f.r(2, 2)) * 180 / M_PI, c = std::atan2(f.r(1, 0), f.r(0, 0)) * 180 / M_PI;
  f.left = EulerToRotation(Eigen::Vector3d(0, 0, c)).transpose();
  f.right = EulerToRotation(Eigen::Vector3d(a, 0, 0)).transpose();
  return f;
}

void TargetForm::Errors(const Eigen::Matrix4d& part_pose, double& mm, double& deg) const {
  const Eigen::Matrix4d q = part_pose * offset;
  mm = (q.topRightCorner<3, 1>() - t).norm();
  const Eigen::Matrix3d R = q.topLeftCorner<3, 3>();
  auto angle = [&](const Eigen::Matrix3d& target) {
    auto between = [](const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
      return std::atan2(u.cross(v).norm(), u.dot(v)) * 180 / M_PI;
    };
    if (ignore == 0) return between(R.col(0), target.col(0));
    if (ignore == 2) return between(R.row(2).transpose(), target.row(2).transpose());
    if (ignore == 1) return between((left * R * right).col(1), (left * target * right).col(1));
    return RotationAngleDeg(R, target);
  };
  deg = angle(r);
  if (has_twin) deg = std::min(deg, angle(twin));
}

}  // namespace fabatlas::assembly::internal
