// fabatlas/assembly/fit_primitive.h — primitive frames derived from part
// meshes, for the frames data/fabhacks/EXAMPLES.md does not state.
//
// A hook or ring is a bent wire: its surface vertices lie on a torus around
// the wire's centre arc. A rod is a cylinder: its vertices spread along its
// axis. From the vertices of the selected region of a mesh:
//   FitArc:  plane (principal components: normal = least-variance direction),
//            centre and radius (least-squares circle in that plane, Kåsa,
//            then refined to mean distance), wire radius (median distance of
//            the vertices from the centre arc), and the angular span the wire
//            covers (360° minus the largest gap between vertex angles);
//            vertices whose in-plane distance from the centre arc exceeds
//            1.6 × the median are dropped and the fit repeated (a shank
//            leaving the arc; works for round wire and flat strip alike).
//   FitAxis: axis = greatest-variance principal direction, centre = middle
//            of the vertices' extent along it, radius = median distance.
// The frames follow the parametrisations of EXAMPLES.md (docs/assembly.md).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "fabatlas/assembly/frame.h"

namespace fabatlas::assembly {

struct ArcFit {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();   // mm
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit; its largest-magnitude component is positive
  double radius = 0;                                  // centre-arc radius, mm
  double wire_radius = 0;                             // mm
  double span_deg = 360;  // angle the wire covers, counter-clockwise about `normal` from `start`
  Eigen::Vector3d start = Eigen::Vector3d::UnitX();  // unit, in-plane direction from the centre to the span's start
  int points = 0;                                    // vertices used in the final fit
};

struct AxisFit {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // mm, middle of the extent along the axis
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();   // unit; largest-magnitude component positive
  double length = 0, radius = 0;                     // mm
  int points = 0;
};

// Throws InputError when fewer than 12 points are given.
ArcFit FitArc(const std::vector<Eigen::Vector3d>& points);
AxisFit FitAxis(const std::vector<Eigen::Vector3d>& points);

// Hook/ring base frame (EXAMPLES.md: point(θ) = T(0, −r′ sin θ, −r′ cos θ),
// the arc in the frame's y–z plane around its origin, x its normal). For a
// hook the θ range [0, arc_angle] is centred on the fitted span (the wire's
// middle is the range's middle); for a ring (arc_angle ≥ 360) θ = 0 lies in
// the direction of −`down` projected into the plane.
Frame ArcFrame(const ArcFit& fit, double arc_angle_deg, const Eigen::Vector3d& down = -Eigen::Vector3d::UnitZ());

// Rod base frame (EXAMPLES.md: T(0, r, (t − ½)L)·R(−90,0,0)·...): origin on
// the axis at the middle, z along the axis, y towards `up` (the side a
// hanging partner rests on) made perpendicular to the axis.
Frame AxisFrame(const AxisFit& fit, const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());

// Euler angles [a,b,c] (degrees) with R = Rz(c)·Ry(b)·Rx(a).
Eigen::Vector3d RotationToEuler(const Eigen::Matrix3d& r);

// The vertices of the mesh at `path` inside the box [lo, hi] (mm, mesh frame).
std::vector<Eigen::Vector3d> MeshPointsIn(const std::string& path, const Eigen::Vector3d& lo,
                                          const Eigen::Vector3d& hi);

}  // namespace fabatlas::assembly
