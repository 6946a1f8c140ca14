// Internal: the 2D subtrees of OpenSCAD's CSG tree as shapes (closed loops
// combined by booleans), their point tests, bounds and signed distances, for
// the level-set road of the `openscad` node (openscad_node.h).
#pragma once

#include <array>
#include <functional>
#include <utility>
#include <vector>

#include "csg_arguments.h"
#include "fabatlas/scad/csg_tree.h"
#include "fabatlas/scad/primitive_mesh.h"

namespace fabatlas::design::csg {

using scad::Loop;

// A 2D shape as closed loops (after the 2D transform) combined by booleans.
struct Shape2 {
  enum class Op { kLoops, kUnion, kDifference, kIntersection } op = Op::kLoops;
  std::vector<Loop> loops;  // kLoops: filled by the even-odd rule
  std::vector<Shape2> parts;
};

// Whether p lies inside the loop (even-odd crossing test).
bool PointInLoop(const scad::Point2& p, const Loop& loop);

// Whether p lies in the shape: an odd number of a loop set's loops, then the booleans.
bool Inside(const Shape2& s, const scad::Point2& p);

// Appends every loop of the shape (its parts' too) to out.
void CollectLoops(const Shape2& s, std::vector<Loop>& out);

// Appends every point of the shape's loops (its parts' too) to out.
void CollectPoints(const Shape2& s, std::vector<scad::Point2>& out);

// 2D transform: rows (a b tx; c d ty).
using Affine2 = std::array<double, 6>;

// The loop mapped by t.
Loop Apply(const Affine2& t, const Loop& l);

// OpenSCAD's own outline of a 2D subtree with no native equivalent (text,
// offset, projection, 2D imports), in the subtree's coordinates.
using Render2 = std::function<std::vector<Loop>(const CsgNode&)>;

// The 2D subtree n under t as a shape; subtrees with no native equivalent
// are render2's outlines. Throws NoNativeEquivalent.
Shape2 Evaluate2(const CsgNode& n, const Affine2& t, const Render2& render2);

// The least and the greatest x over the shape's points and the axis x = 0
// (what rotate_extrude turns about): {min(0, x...), max(0, x...)}.
std::pair<double, double> XRangeWithAxis(const Shape2& s);

// The signed distance (a bound: exact per loop set, min/max across the
// booleans) to a 2D shape; +infinity for nothing.
using Distance2 = std::function<double(double, double)>;

Distance2 RegionOf(const Shape2& s);

// Grows [lo, hi] by the shape's bounding box: of a difference its first
// operand's, of an intersection the overlap of its operands' (so trimming
// with a huge square, `difference() { shape; square(4200); }`, keeps the
// shape's box), of a union every operand's.
void Bounds2(const Shape2& s, scad::Point2& lo, scad::Point2& hi);

}  // namespace fabatlas::design::csg
