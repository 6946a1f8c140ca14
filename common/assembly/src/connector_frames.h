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

// Parametrised part of the connector frame L(s) (PARTS.md §1), without the
// base frame.
template <typename T>
Mat4<T> LocalConnectorFrame(const Primitive& p, const T* s) {
  using std::cos;
  using std::sin;
  const T deg = T(M_PI / 180.0);
  switch (p.type) {
    case PrimitiveType::kRod: {
      const double L = p.Shape("length"), r = p.Shape("radius");
      if (p.ctl)  // RodCtl: on the centre line
        return Translate<T>(T(0), T(0), (s[0] - T(0.5)) * T(L)) * RotAxis<T>(0, T(-90));
      return Translate<T>(T(0), T(r), (s[0] - T(0.5)) * T(L)) * RotAxis<T>(0, T(-90)) * RotAxis<T>(0, s[1] - T(90));
    }
    case PrimitiveType::kHook:
    case PrimitiveType::kRing: {
      if (p.ctl)  // RingCtl: L = R(u2, u1, 0) = Ry(u1)·Rx(u2), at the ring centre
        return RotAxis<T>(1, s[0]) * RotAxis<T>(0, s[1]);
      const double rp = p.Shape("arc_radius") - p.Shape("thickness");
      const T th = s[0];
      Mat4<T> m = Translate<T>(T(0), -T(rp) * sin(th * deg), -T(rp) * cos(th * deg)) * RotAxis<T>(0, -th);
      if (p.flex) m = m * RotAxis<T>(2, s[1] - T(90));
      return m;
    }
    case PrimitiveType::kTube: {
      const double L = p.Shape("length");
      // Tube: outer surface; TubeCtl: inner surface (§1.4).
      const double y = p.Shape("inner_radius") + (p.ctl ? 0.0 : p.Shape("thickness"));
      const T th = s[1];
      return Translate<T>(T(0), T(0), (s[0] - T(0.5)) * T(L)) * RotAxis<T>(0, T(-90)) *
             Translate<T>(-T(y) * sin(th * deg), T(0), -T(y) * cos(th * deg)) * RotAxis<T>(1, th);
    }
    case PrimitiveType::kClip:
      return Translate<T>(T(0), T(0), (s[0] - T(0.5)) * T(p.Shape("height")));
    case PrimitiveType::kEdge:
      return Translate<T>((s[0] - T(0.5)) * T(p.Shape("length")), T(0.5 * p.Shape("width")), T(0));
    case PrimitiveType::kSurface:  // +0.05: the top of the 0.1 mm plate (§1.7)
      return Translate<T>((s[1] - T(0.5)) * T(p.Shape("length")), (T(0.5) - s[0]) * T(p.Shape("width")), T(0.05)) *
             RotAxis<T>(2, s[2]);
    case PrimitiveType::kHemisphere: {
      // T(R sinφ, R cosφ sinθ, −R cosφ cosθ) · R(−θ, φ, 0) · R(0, 0, spin) (§1.8).
      const double R = p.Shape("radius");
      const T th = s[0], ph = s[1];
      return Translate<T>(T(R) * sin(ph * deg), T(R) * cos(ph * deg) * sin(th * deg),
                          -T(R) * cos(ph * deg) * cos(th * deg)) *
             RotAxis<T>(1, ph) * RotAxis<T>(0, -th) * RotAxis<T>(2, s[2]);
    }
  }
  return Mat4<T>::Identity();
}

// Symmetry of a loop-closing connection (PARTS.md §2.4, the class of its
// first primitive): the Euler component a primitive class ignores ("0") is
// one free rotation about that local axis of its connector frame; -1 = none.
// Ring x (its axis), Rod z, Tube y (its axis), Hemisphere z.
inline int SymmetryAxis(PrimitiveType t) {
  switch (t) {
    case PrimitiveType::kRing:
      return 0;
    case PrimitiveType::kRod:
      return 2;
    case PrimitiveType::kTube:
      return 1;
    case PrimitiveType::kHemisphere:
      return 2;
    default:
      return -1;
  }
}

// Number of doubles per connection-parameter block: up to 3 primitive DoFs
// plus the symmetry angle at index 3 (degrees).
inline constexpr int kParamBlock = 4;

// Local frame including the free symmetry rotation s[3] about `axis` (-1: none).
template <typename T>
Mat4<T> SymmetricConnectorFrame(const Primitive& p, const T* s, int axis) {
  Mat4<T> m = LocalConnectorFrame<T>(p, s);
  if (axis >= 0) m = m * RotAxis<T>(axis, s[3]);
  return m;
}

}  // namespace fabatlas::assembly::internal
