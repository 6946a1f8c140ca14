// solve/target_form.h (internal to fabatlas_assembly) — the program's target
// (end_with) as the solve compares it: position in mm and rotation up to the
// symmetry of the end primitive's class.
#pragma once

#include <cmath>

#include <Eigen/Core>

#include "fabatlas/assembly/program.h"
#include "kinematics.h"

namespace fabatlas::assembly::internal {

// The end_with target (PARTS.md §2.1, §2.4): the world frame of the end
// primitive, P·B, against the target frame, position in mm and rotation up
// to the symmetry of the end primitive's class. An Euler component the class
// ignores makes the rotation residual blind to it: a (rotation about the
// local x axis) compares only R·e_x; c (about the world z axis) only the
// third row of R; b only Rz(c_t)ᵀ·R·Rx(a_t)ᵀ·e_y. A period of 180 on c
// (clip, surface) also accepts Rz(180)·R_t. Rotation rows are linear in R, so
// their derivative is the same map applied to dR.
struct TargetForm {
  Eigen::Matrix4d offset = Eigen::Matrix4d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity(), twin = Eigen::Matrix3d::Identity();
  bool has_twin = false;
  int ignore = -1;  // Euler component ignored: 0 a, 1 b, 2 c
  Eigen::Matrix3d left = Eigen::Matrix3d::Identity(), right = Eigen::Matrix3d::Identity();

  // The target of `prog` (its frame, offset and symmetry class).
  static TargetForm Of(const Program& prog);

  // W(R): the rotation quantities compared (9 values; unused ones 0).
  template <typename T>
  void Rows(const Eigen::Matrix<T, 3, 3>& R, T* out) const {
    for (int i = 0; i < 9; ++i) out[i] = T(0);
    if (ignore == 0) {
      for (int i = 0; i < 3; ++i) out[i] = R(i, 0);
    } else if (ignore == 2) {
      for (int i = 0; i < 3; ++i) out[i] = R(2, i);
    } else if (ignore == 1) {
      const Eigen::Matrix<T, 3, 3> m = left.cast<T>() * R * right.cast<T>();
      for (int i = 0; i < 3; ++i) out[i] = m(i, 1);
    } else {
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) out[3 * i + j] = R(i, j);
    }
  }

  // W(R) − W(target), with the nearer of the target and its twin.
  template <typename T>
  void RotationResidual(const Eigen::Matrix<T, 3, 3>& R, T* out) const {
    T w[9];
    Rows<T>(R, w);
    double t1[9], t2[9];
    Rows<double>(r, t1);
    Rows<double>(twin, t2);
    double d1 = 0, d2 = 0;
    for (int i = 0; i < 9; ++i) d1 += std::pow(Value(w[i]) - t1[i], 2), d2 += std::pow(Value(w[i]) - t2[i], 2);
    const double* tt = has_twin && d2 < d1 ? t2 : t1;
    for (int i = 0; i < 9; ++i) out[i] = w[i] - T(tt[i]);
  }

  // Position error (mm) and rotation error (degrees) up to the symmetry.
  void Errors(const Eigen::Matrix4d& part_pose, double& mm, double& deg) const;
};

}  // namespace fabatlas::assembly::internal
