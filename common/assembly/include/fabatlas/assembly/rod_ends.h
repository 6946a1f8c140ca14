// fabatlas/assembly/rod_ends.h — what a part's mesh puts past each end of
// one of its rods.
//
// A connector on a rod slides off an end only if nothing is there (FabHacks
// 4.3.3: "hooks or rings that slide past the end of the dowel rod fall off").
// The part's mesh says whether the part's body continues past an end (a wall
// the peg stands out of, a knob or plug wider than the rod): the data's
// open/closed flags (`clamped`, `blocked`) can be checked against it.
//
// A rod's t runs along its base frame's z axis, t = 0 at z = −L/2 and t = 1 at
// z = +L/2 (PARTS.md §1.1; the same for RodCtl). For each end, points on the
// axis continued past it are probed at the given distances:
//   distance_mm      distance from the point to the nearest mesh triangle;
//   rays_hit         of `rays` directions (a Fibonacci sphere), how many
//                    meet the mesh within max_ray_mm;
//   hits_from_inside how many of those first meet a triangle from its back
//                    (the side its winding normal points away from).
// A point is inside the part's body (`Enclosed`) when at least a third of
// the rays meet the mesh and at least 95 % of them from behind: the mesh is
// around it, facing away. Works on open scans (a room scanned from inside:
// behind its wall is inside) as long as the triangles are wound with outward
// normals.
//
// Brute force over all triangles: O(probes × rays × triangles);
// single-threaded; triangles farther than max_ray_mm are skipped for the rays
// (readingroom.stl, 26,497 triangles: ~15 ms per probe).
#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "fabatlas/assembly/mass_properties.h"
#include "fabatlas/assembly/part_library.h"

namespace fabatlas::assembly {

struct RodEndOptions {
  std::vector<double> probe_mm = {5, 10, 20, 40};  // distances past the end along the axis, mm
  int rays = 200;
  double max_ray_mm = 200;
};

struct RodEndProbe {
  double past_mm = 0;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // part frame, mm
  double distance_mm = 0;
  int rays_hit = 0, hits_from_inside = 0, rays = 0;
  bool Enclosed() const { return 3 * rays_hit >= rays && 100 * hits_from_inside >= 95 * rays_hit; }
};

struct RodEnd {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // centre of the end face, part frame, mm
  Eigen::Vector3d outward = Eigen::Vector3d::UnitZ();  // unit, along the axis away from the rod
  std::vector<RodEndProbe> probes;
};

struct RodEnds {
  RodEnd t0, t1;  // the ends at t = 0 (min) and t = 1 (max)
};

// `rod` must be a rod primitive of the part whose mesh is `mesh` (both in the
// part frame). Throws std::invalid_argument for another primitive type.
RodEnds MeasureRodEnds(const PartMesh& mesh, const Primitive& rod, const RodEndOptions& options = {});

}  // namespace fabatlas::assembly
