// fabatlas/scad/region_outline.h — the outline and a triangulation of a
// planar region given by loops and a membership test (the result of
// OpenSCAD's 2D booleans and even-odd polygons), as OpenSCAD extrudes it:
// a twisted or non-uniformly scaled linear_extrude builds its side walls
// from the outline of the whole 2D child, so extruding each loop and
// combining the solids in 3D is not the same mesh (docs/openscad.md,
// "Native evaluation"). Millimetres.
#pragma once

#include <array>
#include <functional>
#include <vector>

#include "fabatlas/scad/primitive_mesh.h"

namespace fabatlas::scad {

// The region inside(p) of the arrangement of `loops`' edges: a constrained
// Delaunay triangulation of every edge (CGAL, exact predicates; crossings
// become vertices), each triangle kept when inside() holds at its centroid,
// the boundary traced between kept and dropped triangles. inside() must be
// constant on each face of the arrangement (a boolean of the loops' even-odd
// regions is). Cost O(E log E) for E edges plus E calls of inside().
// Single-threaded.
Region2 ResolveRegion(const std::vector<Loop>& loops, const std::function<bool(const Point2&)>& inside);

}  // namespace fabatlas::scad
