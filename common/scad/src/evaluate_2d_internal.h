// evaluate_2d_internal.h (internal to fabatlas_scad) — the step the
// extrusions share with Evaluate2d.
#pragma once

#include <string>
#include <vector>

#include "fabatlas/scad/evaluate_2d.h"

namespace fabatlas::scad::internal {

// The union of a node's 2-D children as OpenSCAD's applyToChildren2D(UNION)
// computes it for linear_extrude, rotate_extrude and offset: 3-D children
// ignored with OpenSCAD's warning, one child copied, several unioned.
Polygon2d UnionOfChildren(const CsgNode& node, const Evaluate2dOptions& options, std::vector<std::string>* warnings);

}  // namespace fabatlas::scad::internal
