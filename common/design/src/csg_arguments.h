// Internal: reading the arguments of a node of OpenSCAD's CSG tree (numbers,
// fragment counts) and which nodes are 2D, for the `openscad` node's own
// evaluation (openscad_node.h).
#pragma once

#include <string>
#include <vector>

#include "fabatlas/scad/csg_tree.h"

namespace fabatlas::design::csg {

using scad::CsgNode;
using scad::CsgValue;

// A subtree OpenSCAD must render: thrown by the 2D evaluation up to the
// enclosing 3D node.
struct NoNativeEquivalent {
  std::string what;
};

bool IsTwoD(const std::string& name);

// Nodes that are 3D whatever their children (OpenSCAD ignores them under a
// 2D operation).
bool IsThreeD(const std::string& name);

// v's number, else `fallback`.
double Num(const CsgValue& v, double fallback);

// v's items as numbers (0 for an item that is not one).
std::vector<double> Numbers(const CsgValue& v);

// The fragments of a circle of radius r under n's $fn, $fs, $fa.
int FragmentsOf(const CsgNode& n, double r);

}  // namespace fabatlas::design::csg
