// fabatlas/swept/rigid_motion.h — keyframed rigid motions of reconfigurables.
//
// Reconfigurables (section 3) animates each object of a reconfigurable by a rigid
// motion f(t), t in [0,1], along a transition between two states. Here a
// motion is a cubic Bezier curve for the translation and a chain of unit
// quaternion keyframes, interpolated by slerp, for the rotation:
//
//   f(t) x = R(t) (x - pivot) + pivot + T(t)
//   T(t)   = (1-t)^3 P0 + 3(1-t)^2 t P1 + 3(1-t) t^2 P2 + t^3 P3
//   R(t)   = slerp(q_i, q_{i+1}, s) with keys evenly spaced in t:
//            K keys, i = floor(t (K-1)), s = t (K-1) - i.
//
// The slerp follows the great arc from q_i to q_{i+1} as given (no sign flip
// to the shortest arc), so a full turn is written as keys of less than 180
// degrees each: see RigidMotion::Turn. Units: millimetres and degrees.
#pragma once

#include <array>
#include <vector>

#include "fabatlas/vec3.h"

namespace fabatlas::swept {

using fabatlas::Vec3;

// Unit quaternion w + xi + yj + zk (normalised on use).
struct Quaternion {
  double w = 1, x = 0, y = 0, z = 0;
  // Rotation by angle_deg about axis (any non-zero length; right-hand rule).
  static Quaternion FromAxisAngle(const Vec3& axis, double angle_deg);
};

// x -> rotation * x + translation (rotation row-major, orthonormal).
struct Transform {
  std::array<Vec3, 3> rotation{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  Vec3 translation{0, 0, 0};

  Vec3 Apply(const Vec3& x) const;
  Transform Inverse() const;
  // (this * other) x = this(other(x)).
  Transform Compose(const Transform& other) const;
};

struct RigidMotion {
  // Control points P0..P3 of the translation T(t), mm. Default: no translation.
  std::array<Vec3, 4> translation{};
  // Rotation keyframes, evenly spaced over t in [0,1]. Empty = no rotation;
  // one key = constant rotation.
  std::vector<Quaternion> rotation_keys;
  // Centre of the rotation in body coordinates, mm.
  Vec3 pivot{0, 0, 0};

  // The pose at time t (clamped to [0,1]). Throws InputError if t is not
  // finite or a rotation key has zero length.
  Transform At(double t) const;

  // An upper bound on |d/dt f(t) x| over t in [0,1] for every body point x
  // within `radius` mm of the pivot (mm per unit t): the largest control
  // point of T' (a quadratic Bezier with control points 3 (P_k+1 - P_k), so
  // |T'| stays below the largest of them) plus radius times the largest
  // angular speed, 2 theta_i (K - 1) for the slerp between keys i and i+1 at
  // quaternion angle theta_i. Used by conservative advancement
  // (continuous_contact.h).
  double SpeedBound(double radius) const;

  // A straight translation from `from` to `to` at constant speed.
  static RigidMotion Line(const Vec3& from, const Vec3& to);
  // A turn by total_deg about `axis` through `pivot` at constant angular
  // speed, written as keys of at most 90 degrees each.
  static RigidMotion Turn(const Vec3& axis, double total_deg, const Vec3& pivot);
};

// Relative motion of B observed in A's frame (Reconfigurables, Eq. 4: f_A^-1 o f_B).
// The result is evaluated pointwise; it is not a RigidMotion (a relative
// motion is not in general a Bezier/slerp pair), hence a sampled list of
// transforms at t_i = i/(steps-1).
std::vector<Transform> SampleRelativeMotion(const RigidMotion& a, const RigidMotion& b, int steps);

}  // namespace fabatlas::swept
