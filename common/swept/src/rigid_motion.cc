// Keyframed rigid motions (Reconfigurables, section 3): cubic Bezier translation and
// slerp between quaternion keys.
#include "fabatlas/swept/rigid_motion.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "fabatlas/error.h"

namespace fabatlas::swept {
namespace {

Quaternion Normalised(const Quaternion& q, std::size_t index) {
  const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (!(n > 1e-12) || !std::isfinite(n)) {
    throw InputError("rigid motion: rotation key " + std::to_string(index) + " has zero or non-finite length");
  }
  return {q.w / n, q.x / n, q.y / n, q.z / n};
}

// Slerp along the great arc from a to b as given (unit inputs).
Quaternion Slerp(const Quaternion& a, const Quaternion& b, double s) {
  double d = a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z;
  d = std::clamp(d, -1.0, 1.0);
  const double theta = std::acos(d);
  double wa, wb;
  if (std::sin(theta) < 1e-9) {  // (anti)parallel keys: linear blend then normalise
    wa = 1 - s;
    wb = s;
  } else {
    wa = std::sin((1 - s) * theta) / std::sin(theta);
    wb = std::sin(s * theta) / std::sin(theta);
  }
  Quaternion q{wa * a.w + wb * b.w, wa * a.x + wb * b.x, wa * a.y + wb * b.y, wa * a.z + wb * b.z};
  return Normalised(q, 0);
}

std::array<std::array<double, 3>, 3> ToMatrix(const Quaternion& q) {
  const double w = q.w, x = q.x, y = q.y, z = q.z;
  return {{{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
           {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
           {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}}};
}

}  // namespace

Quaternion Quaternion::FromAxisAngle(const Vec3& axis, double angle_deg) {
  const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  if (!(n > 0) || !std::isfinite(n) || !std::isfinite(angle_deg)) {
    throw InputError("rigid motion: rotation axis must be non-zero and finite");
  }
  const double half = 0.5 * angle_deg * std::numbers::pi / 180.0;
  const double s = std::sin(half) / n;
  return {std::cos(half), axis[0] * s, axis[1] * s, axis[2] * s};
}

Vec3 Transform::Apply(const Vec3& x) const {
  Vec3 y;
  for (int r = 0; r < 3; ++r) {
    y[r] = rotation[r][0] * x[0] + rotation[r][1] * x[1] + rotation[r][2] * x[2] + translation[r];
  }
  return y;
}

Transform Transform::Inverse() const {
  Transform inv;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) inv.rotation[r][c] = rotation[c][r];
  for (int r = 0; r < 3; ++r) {
    inv.translation[r] = -(inv.rotation[r][0] * translation[0] + inv.rotation[r][1] * translation[1] +
                           inv.rotation[r][2] * translation[2]);
  }
  return inv;
}

Transform Transform::Compose(const Transform& o) const {
  Transform out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      out.rotation[r][c] =
          rotation[r][0] * o.rotation[0][c] + rotation[r][1] * o.rotation[1][c] + rotation[r][2] * o.rotation[2][c];
    }
  }
  const Vec3 t = Apply(o.translation);
  out.translation = t;
  return out;
}

Transform RigidMotion::At(double t) const {
  if (!std::isfinite(t)) throw InputError("rigid motion: time is not finite");
  t = std::clamp(t, 0.0, 1.0);
  Transform f;
  if (!rotation_keys.empty()) {
    Quaternion q;
    if (rotation_keys.size() == 1) {
      q = Normalised(rotation_keys[0], 0);
    } else {
      const double u = t * static_cast<double>(rotation_keys.size() - 1);
      const std::size_t i = std::min(static_cast<std::size_t>(u), rotation_keys.size() - 2);
      q = Slerp(Normalised(rotation_keys[i], i), Normalised(rotation_keys[i + 1], i + 1), u - static_cast<double>(i));
    }
    f.rotation = ToMatrix(q);
  }
  const double a = (1 - t) * (1 - t) * (1 - t), b = 3 * (1 - t) * (1 - t) * t, c = 3 * (1 - t) * t * t, d = t * t * t;
  // f(x) = R (x - pivot) + pivot + T(t)
  for (int r = 0; r < 3; ++r) {
    const double rp = f.rotation[r][0] * pivot[0] + f.rotation[r][1] * pivot[1] + f.rotation[r][2] * pivot[2];
    f.translation[r] =
        pivot[r] - rp + a * translation[0][r] + b * translation[1][r] + c * translation[2][r] + d * translation[3][r];
  }
  return f;
}

double RigidMotion::SpeedBound(double radius) const {
  double linear = 0;
  for (int k = 0; k < 3; ++k) {
    const double dx = translation[k + 1][0] - translation[k][0], dy = translation[k + 1][1] - translation[k][1],
                 dz = translation[k + 1][2] - translation[k][2];
    linear = std::max(linear, 3 * std::sqrt(dx * dx + dy * dy + dz * dz));
  }
  double angular = 0;
  for (std::size_t i = 0; i + 1 < rotation_keys.size(); ++i) {
    const Quaternion a = Normalised(rotation_keys[i], i), b = Normalised(rotation_keys[i + 1], i + 1);
    const double d = std::clamp(a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z, -1.0, 1.0);
    angular = std::max(angular, 2 * std::acos(d) * static_cast<double>(rotation_keys.size() - 1));
  }
  return linear + radius * angular;
}

RigidMotion RigidMotion::Line(const Vec3& from, const Vec3& to) {
  RigidMotion m;
  for (int k = 0; k < 4; ++k)
    for (int r = 0; r < 3; ++r) m.translation[k][r] = from[r] + (to[r] - from[r]) * k / 3.0;
  return m;
}

RigidMotion RigidMotion::Turn(const Vec3& axis, double total_deg, const Vec3& pivot) {
  if (!std::isfinite(total_deg)) throw InputError("rigid motion: turn angle is not finite");
  RigidMotion m;
  m.pivot = pivot;
  const int pieces = std::max(1, static_cast<int>(std::ceil(std::abs(total_deg) / 90.0)));
  for (int i = 0; i <= pieces; ++i) m.rotation_keys.push_back(Quaternion::FromAxisAngle(axis, total_deg * i / pieces));
  return m;
}

std::vector<Transform> SampleRelativeMotion(const RigidMotion& a, const RigidMotion& b, int steps) {
  if (steps < 2) throw InputError("relative motion: need at least 2 time steps");
  std::vector<Transform> out;
  out.reserve(steps);
  for (int i = 0; i < steps; ++i) {
    const double t = static_cast<double>(i) / (steps - 1);
    out.push_back(a.At(t).Inverse().Compose(b.At(t)));
  }
  return out;
}

}  // namespace fabatlas::swept
