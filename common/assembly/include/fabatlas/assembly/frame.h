// fabatlas/assembly/frame.h — rigid frames of FabHaL (FabHacks, section 4.1).
//
// A Frame is a position (mm) and three Euler angles [a,b,c] in degrees with
// R = Rz(c)·Ry(b)·Rx(a) (the convention of the FabHacks reference, see
// data/fabhacks/EXAMPLES.md; "yaw, pitch, roll" there name a, b, c).
#pragma once

#include <Eigen/Geometry>

namespace fabatlas::assembly {

struct Frame {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();   // mm
  Eigen::Vector3d euler_deg = Eigen::Vector3d::Zero();  // [a,b,c], degrees
};

// R = Rz(c)·Ry(b)·Rx(a), angles in degrees.
Eigen::Matrix3d EulerToRotation(const Eigen::Vector3d& euler_deg);

// Homogeneous transform of a frame.
Eigen::Isometry3d ToIsometry(const Frame& frame);

// Angle (degrees) of the relative rotation between two rotations.
double RotationAngleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b);

}  // namespace fabatlas::assembly
