// Templated connector-frame math shared by the Ceres residuals (autodiff) and
// the double-precision API. Rotations R(a,b,c) = Rz(c)·Ry(b)·Rx(a), degrees.
#pragma once

#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "fabatlas/assembly/part_library.h"

namespace fabatlas::assembly::internal {

template <typename T>
using Mat4 = Eigen::Matrix<T, 4, 4>;

template <typename T>
Mat4<T> Translate(T x, T y, T z) {
  Mat4<T> m = Mat4<T>::Identity();
  m(0, 3) = x;
  m(1, 3) = y;
  m(2, 3) = z;
  return m;
}

template <typename T>
Mat4<T> RotAxis(int axis, T deg) {
  using std::cos;
  using std::sin;
  const T r = deg * T(M_PI / 180.0);
  const T c = cos(r), s = sin(r);
  Mat4<T> m = Mat4<T>::Identity();
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  m(i, i) = c;
  m(i, j) = -s;
  m(j, i) = s;
  m(j, j) = c;
  return m;
}

template <typename T>
Mat4<T> Rot(T a, T b, T c) {
  return RotAxis<T>(2, c) * RotAxis<T>(1, b) * RotAxis<T>(0, a);
}

// Parametrised part of the connector frame (EXAMPLES.md), without base frame.
template <typename T>
Mat4<T> LocalConnectorFrame(const Primitive& p, const T* s) {
  using std::cos;
  using std::sin;
  const T deg = T(M_PI / 180.0);
  switch (p.type) {
    case PrimitiveType::kRod: {
      const double L = p.Shape("length"), r = p.Shape("radius");
      return Translate<T>(T(0), T(r), (s[0] - T(0.5)) * T(L)) * RotAxis<T>(0, T(-90)) *
             RotAxis<T>(0, s[1] - T(90));
    }
    case PrimitiveType::kHook:
    case PrimitiveType::kRing: {
      const double rp = p.Shape("arc_radius") - p.Shape("thickness");
      const T th = s[0];
      Mat4<T> m = Translate<T>(T(0), -T(rp) * sin(th * deg), -T(rp) * cos(th * deg)) *
                  RotAxis<T>(0, -th);
      if (p.flex) m = m * RotAxis<T>(2, s[1] - T(90));
      return m;
    }
    case PrimitiveType::kTube: {
      const double L = p.Shape("length");
      const double y = p.Shape("inner_radius") + p.Shape("thickness");
      const T th = s[1];
      return Translate<T>(T(0), T(0), (s[0] - T(0.5)) * T(L)) * RotAxis<T>(0, T(-90)) *
             Translate<T>(-T(y) * sin(th * deg), T(0), -T(y) * cos(th * deg)) * RotAxis<T>(1, th);
    }
    case PrimitiveType::kClip:
      return Translate<T>(T(0), T(0), (s[0] - T(0.5)) * T(p.Shape("height")));
    case PrimitiveType::kEdge:
      return Translate<T>((s[0] - T(0.5)) * T(p.Shape("length")), T(0.5 * p.Shape("width")), T(0));
    case PrimitiveType::kSurface:
      return Translate<T>((s[1] - T(0.5)) * T(p.Shape("length")),
                          (T(0.5) - s[0]) * T(p.Shape("width")), T(0)) *
             RotAxis<T>(2, s[2]);
    case PrimitiveType::kHemisphere:
      // Point (theta, phi) on the sphere, frame z pointing into the body so
      // that a hemisphere resting on a surface aligns with identity offset.
      return RotAxis<T>(2, s[0]) * RotAxis<T>(1, s[1]) * Translate<T>(T(0), T(0), T(p.Shape("radius"))) *
             RotAxis<T>(0, T(180)) * RotAxis<T>(2, s[2]);
  }
  return Mat4<T>::Identity();
}

// Symmetry (EXAMPLES.md): the Euler component a primitive ignores ("0") is a
// free rotation about that local axis of its connector frame; -1 = none.
// Clip/Edge/Hook/Surface ignore none, Ring x, Rod z, Tube y, Hemisphere z.
inline int SymmetryAxis(PrimitiveType t) {
  switch (t) {
    case PrimitiveType::kRing: return 0;
    case PrimitiveType::kRod: return 2;
    case PrimitiveType::kTube: return 1;
    case PrimitiveType::kHemisphere: return 2;
    default: return -1;
  }
}

// Number of doubles per connection-parameter block: up to 3 primitive DoFs
// plus the symmetry angle at index 3 (degrees).
inline constexpr int kParamBlock = 4;

// Local frame including the free symmetry rotation s[3].
template <typename T>
Mat4<T> SymmetricConnectorFrame(const Primitive& p, const T* s) {
  const int axis = SymmetryAxis(p.type);
  Mat4<T> m = LocalConnectorFrame<T>(p, s);
  if (axis >= 0) m = m * RotAxis<T>(axis, s[3]);
  return m;
}

}  // namespace fabatlas::assembly::internal
