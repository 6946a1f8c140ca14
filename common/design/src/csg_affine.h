// Internal: affine maps of 3D space as OpenSCAD's CSG tree composes them
// (multmatrix), for the `openscad` node's own evaluation (openscad_node.h).
#pragma once

#include <array>
#include <string>

#include "fabatlas/mesh/triangle_mesh.h"
#include "fabatlas/scad/csg_tree.h"

namespace fabatlas::design::csg {

// An affine map x -> A x + t, row-major 3x4.
using Affine = std::array<double, 12>;
constexpr Affine kIdentity = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

// a after b.
Affine Compose(const Affine& a, const Affine& b);

// The map's 12 numbers as OpenSCAD writes numbers, each followed by a comma
// (part of a subtree's cache key).
std::string AffineText(const Affine& a);

// Maps every vertex of m by a, in place.
void Transform(mesh::TriangleMesh& m, const Affine& a);

// multmatrix(m): the 4x4 argument as an affine map. Throws
// NoNativeEquivalent (csg_arguments.h) for a missing or short matrix or a
// projective last row.
Affine MatrixOf(const scad::CsgNode& n);

// The scale s of an affine map whose linear part is s times a rotation or
// reflection (A^T A = s^2 I), else 0: signed distances map exactly through it.
double SimilarityScale(const Affine& a);

}  // namespace fabatlas::design::csg
