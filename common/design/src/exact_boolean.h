// Internal: exact mesh booleans (CGAL corefinement) for nodes that ask for
// them with `exact: true`.
#pragma once

#include <string>
#include <vector>

#include "fabatlas/geometry/solid.h"
#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::design {

// op is "union", "difference" (first minus the rest) or "intersection".
// Inputs must be closed, non-self-intersecting triangle meshes; otherwise a
// SampleFailure of type no_geometry names which operand is at fault.
mesh::TriangleMesh ExactMeshBoolean(const std::string& op, const std::vector<mesh::TriangleMesh>& operands);

// The level set on `grid` of a closed triangle mesh that an exact boolean
// produced: outward shells are material, inward shells (cavities) are
// subtracted from it.
geometry::Solid SolidOfExactResult(const mesh::TriangleMesh& result, const geometry::GridSpec& grid);

// Meshes every child, runs ExactMeshBoolean, and returns the level set of the
// exact result on the design's grid.
geometry::Solid ExactBoolean(const std::string& op, const std::vector<geometry::Solid>& children,
                             const geometry::GridSpec& grid);

}  // namespace fabatlas::design
