// clipper_shape.h (internal to fabatlas_scad) — OpenSCAD 2021.01's 2-D
// geometry and the Clipper 6.4.2 operations it applies to it, behaviour for
// behaviour: the integer grid (mm times 2^16, truncated toward zero), the
// fill rules (a leaf's paths even-odd, booleans non-zero), the cleaning of
// every result (ClipperLib::CleanPolygon, loops under 3 vertices dropped).
#pragma once

#include <string>
#include <vector>

#include <polyclipping/clipper.hpp>

#include "fabatlas/mesh/triangle_mesh.h"
#include "fabatlas/scad/primitive_mesh.h"

namespace fabatlas::scad::internal {

// OpenSCAD's Polygon2d: its outlines, and whether they came out of Clipper
// (`sanitized`: outer loops counter-clockwise, holes clockwise, simple).
// Loops that did not (a leaf's own circle or square, a hull) are made
// counter-clockwise when they enter Clipper, as OpenSCAD makes them.
struct Shape {
  std::vector<Loop> loops;
  bool sanitized = true;
};

inline constexpr double kClipperScale = 65536.0;  // OpenSCAD 2021.01's CLIPPER_SCALE, 2^16

ClipperLib::Paths ToPaths(const Shape& shape);
Shape FromTree(const ClipperLib::PolyTree& tree);

// A leaf's loops filled even-odd (OpenSCAD's sanitize).
Shape Sanitize(const Shape& shape, std::vector<std::string>* warnings);

// union / difference / intersection of shapes in order (nullptr: an empty
// child, still the subject when first), non-zero fill; intersection as a
// chain of binary intersections. Unsanitized inputs are sanitized first.
Shape Clip(const std::vector<const Shape*>& shapes, ClipperLib::ClipType op, std::vector<std::string>* warnings);

// offset: each loop offset by `delta` mm (join kind, miter limit, arc
// tolerance in mm as OpenSCAD derives it from $fn/$fa/$fs).
Shape Offset(const Shape& shape, double delta, ClipperLib::JoinType join, double miter_limit, double arc_tolerance);

// minkowski of 2-D children: OpenSCAD's convolution of every pair of loops
// (quads between the translated copies, not Clipper's own MinkowskiSum) plus
// each polygon placed at a vertex of each outer loop of the other, unioned
// non-zero. A null child after the first is skipped; one child is copied.
Shape Minkowski(const std::vector<const Shape*>& shapes);

// projection(cut = false) of 3-D children: each triangle projected to z = 0
// and turned counter-clockwise, each child's unioned non-zero, then all of
// them (strictly simple).
Shape Shadow(const std::vector<mesh::TriangleMesh>& meshes);

// projection(cut = true): the closed set where the solids meet z = 0 (a
// face lying in the plane included), as loops through Clipper.
Shape Section(const std::vector<mesh::TriangleMesh>& meshes);

}  // namespace fabatlas::scad::internal
