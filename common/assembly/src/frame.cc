#include "fabatlas/assembly/frame.h"

#include <algorithm>
#include <cmath>

namespace fabatlas::assembly {

Eigen::Matrix3d EulerToRotation(const Eigen::Vector3d& e) {
  const double k = M_PI / 180.0;
  return (Eigen::AngleAxisd(e.z() * k, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(e.y() * k, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(e.x() * k, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Isometry3d ToIsometry(const Frame& f) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = EulerToRotation(f.euler_deg);
  t.translation() = f.position;
  return t;
}

double RotationAngleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const double c = std::clamp(((a.transpose() * b).trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c) * 180.0 / M_PI;
}

}  // namespace fabatlas::assembly
