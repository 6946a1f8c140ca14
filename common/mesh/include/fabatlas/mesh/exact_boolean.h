// fabatlas/mesh/exact_boolean.h — exact booleans of closed triangle meshes
// (CGAL Polygon_mesh_processing corefinement on Surface_mesh<Epick>).
//
// The one implementation of an exact mesh union, difference or intersection:
// the design's `exact: true` nodes and carve_swept, and swept::Subtract, use
// it. Units are the meshes' own. Single-threaded.
#pragma once

#include <vector>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::mesh {

enum class BooleanOp { kUnion, kDifference, kIntersection };

// operands[0] op operands[1] op ... (difference: the first minus the rest).
// Every operand must be a closed, manifold, non-self-intersecting triangle
// mesh; otherwise, or when CGAL cannot produce a manifold result, throws
// InputError whose message names the operand by index ("exact boolean operand
// 1 is not closed"). An empty result has no triangles.
TriangleMesh ExactBoolean(BooleanOp op, const std::vector<TriangleMesh>& operands);

// "union", "difference", "intersection".
const char* BooleanOpName(BooleanOp op);

}  // namespace fabatlas::mesh
