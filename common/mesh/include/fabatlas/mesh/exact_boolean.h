// fabatlas/mesh/exact_boolean.h — exact booleans of closed triangle meshes:
// CGAL Polygon Mesh Processing corefinement on Surface_mesh, with exact
// predicates always and the intersection points constructed in doubles
// first (Epick: rounded once, as the result is rounded anyway), redone with
// exact constructions (Epeck) when that result is not closed or touches
// itself, and CGAL's Nef polyhedra (the exact booleans OpenSCAD 2021.01
// computes everything with) as the fallback where corefinement cannot give
// a manifold result (two boxes sharing an edge) or an operand touches itself.
//
// The one implementation of a mesh union, difference or intersection: the
// mesh road of OpenSCAD models (docs/openscad.md), the design's `exact: true`
// nodes, carve_swept and swept::Subtract use it. Every operation is exact;
// its result is rounded to doubles once, when it is returned. Units are the
// meshes' own. Single-threaded; reentrant (no shared state).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "fabatlas/mesh/triangle_mesh.h"
#include "fabatlas/vec3.h"

namespace fabatlas::mesh {

enum class BooleanOp { kUnion, kDifference, kIntersection };

// What a boolean did (for the sample's log and benchmarks).
struct BooleanSummary {
  int corefinements = 0;        // pairwise corefinements run
  int exact_corefinements = 0;  // of them, those the kernel with exact constructions had to redo
  int disjoint = 0;             // operands settled by their bounding boxes alone (no intersection computed)
  int nef = 0;                  // operations that fell back to Nef polyhedra
  std::string nef_why;          // why the first fallback was taken, "" when none
};

// How a boolean may compute its result.
struct BooleanOptions {
  // Where corefinement in doubles gives no closed result, redo it with
  // exact constructions, then with CGAL's Nef polyhedra (both exact, and
  // orders of magnitude slower on many coplanar faces: minutes on a few
  // thousand triangles). false: throw InputError instead, for callers with
  // a cheaper answer of their own (ΔG's level sets).
  bool exact_fallbacks = true;
};

// operands[0] op operands[1] op ... (difference: the first minus the rest).
// Each operand must be a closed triangle mesh (either orientation: an
// inward one is flipped, as OpenSCAD flips inverted polyhedra); an empty
// operand is no material. Operands whose bounding boxes do not meet are
// settled without an intersection: joined (union), dropped (difference) or
// the result is empty (intersection). Throws InputError naming the operand
// by index ("exact boolean operand 1 is not closed") when an operand is not
// closed or has a triangle with a missing vertex, or when neither
// corefinement nor Nef polyhedra can compute the result (or corefinement in
// doubles cannot and options.exact_fallbacks is false). The result is
// closed; it is manifold except where the exact result is not (Nef's
// output, e.g. two boxes sharing an edge: the edge is kept once per side).
TriangleMesh ExactBoolean(BooleanOp op, const std::vector<TriangleMesh>& operands, BooleanSummary* summary = nullptr,
                          const BooleanOptions& options = {});

// "union", "difference", "intersection".
const char* BooleanOpName(BooleanOp op);

// The convex hull of points (exact predicates: the hull's vertices are input
// points) as a closed outward triangle mesh; empty when the points span no
// volume (fewer than 4, or all in one plane).
TriangleMesh ConvexHull(const std::vector<Vec3>& points);

// The Minkowski sum of closed triangle meshes, as OpenSCAD 2021.01 computes
// it: each operand is split into convex parts (a convex operand is one part;
// otherwise CGAL's Nef convex decomposition), the sum of two convex parts is
// the convex hull of their vertices' pairwise sums, and the result is the
// union of those hulls. Empty operands are skipped. Throws InputError as
// ExactBoolean does.
TriangleMesh MinkowskiSum(const std::vector<TriangleMesh>& operands, BooleanSummary* summary = nullptr);

}  // namespace fabatlas::mesh
