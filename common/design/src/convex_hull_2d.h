// The convex hull of points in the plane (internal to fabatlas_design): the
// outline a 2D OpenSCAD hull() makes and the base polygon of the stability
// check.
#pragma once

#include <vector>

#include "fabatlas/vec3.h"

namespace fabatlas::design {

// Andrew's monotone chain (docs/references.md). Input: points in any order, repeats allowed. Output: the hull's
// vertices counter-clockwise from the lowest-x (then lowest-y) point, without
// collinear or repeated vertices; fewer than 3 when the points are collinear
// (then the distinct points if fewer than 3, else the two extremes).
// O(n log n).
std::vector<Vec2> ConvexHull2D(std::vector<Vec2> points);

}  // namespace fabatlas::design
