// fabatlas/scad/csg_bounds.h — a box around the solid of an OpenSCAD CSG tree
// (csg_tree.h), read from the nodes' arguments without any boolean or mesh:
// a union's (group, hull, color, render) box is the union of its children's,
// a difference's is its first operand's, an intersection's the overlap of its
// operands', a minkowski's the sum of its operands', a multmatrix's the box
// of its child box's eight corners mapped by the matrix.
//
// Exact for a cube, cylinder, polyhedron, square or polygon under translations
// and axis scalings and for unions of them; conservative (the box holds the
// solid, may be larger) elsewhere: a sphere or circle is bounded by its radius
// (OpenSCAD's polygon lies inside it), a rotated box by its rotated corners, a
// difference by its first operand, a twisted linear_extrude by the circle its
// outline sweeps, a rotate_extrude by a full turn, an offset by its outline's
// box grown by |r| or delta.
#pragma once

#include <array>
#include <string>

#include "fabatlas/scad/csg_tree.h"

namespace fabatlas::scad {

struct CsgBox {
  // false: a node's extent is not in its arguments (import, surface, text,
  // resize, or a node OpenSCAD 2021.01's CSG export does not write);
  // `unknown` names it ("LINE: NAME").
  bool known = true;
  std::string unknown;
  // Known and no 3-D material (no 3-D node, or an intersection of disjoint
  // boxes): lo and hi are meaningless.
  bool empty = true;
  std::array<double, 3> lo{0, 0, 0}, hi{0, 0, 0};  // mm
};

// The box of the 3-D solid `root` describes (2-D shapes count only inside an
// extrusion). Never throws; a malformed argument makes the box unknown.
CsgBox CsgBounds(const CsgNode& root);

}  // namespace fabatlas::scad
