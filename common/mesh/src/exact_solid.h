// exact_solid.h — the exact operand of ExactBoolean (internal): a closed
// surface mesh with exact points (CGAL's Epeck kernel), or a Nef polyhedron
// where the exact result is not a 2-manifold.
//
// The steps of exact_boolean.h, one file each so that each compiles only the
// CGAL templates it uses and the files build in parallel:
//   exact_operand.cc       a TriangleMesh as an Exact and back
//   float_corefinement.cc  corefinement in doubles (Epick)
//   exact_corefinement.cc  corefinement with exact constructions (Epeck)
//   nef_boolean.cc         Nef polyhedra: the fallback (nef_solid.h)
//   convex_parts.cc        Nef convex decomposition (MinkowskiSum's operands)
//   convex_hull.cc, minkowski_sum.cc, exact_boolean.cc (the order of the steps)
#pragma once

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>

#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fabatlas/mesh/exact_boolean.h"
#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::mesh::internal {

using Kernel = CGAL::Exact_predicates_exact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;

// A Nef polyhedron of Kernel (nef_solid.h); never changed once made.
struct NefSolid;

// An exact operand or intermediate result: a closed surface mesh, or a Nef
// polyhedron where the exact result is not a 2-manifold.
struct Exact {
  SurfaceMesh mesh;
  std::shared_ptr<const NefSolid> nef;  // null: `mesh` is the solid
  CGAL::Bbox_3 box;
  bool empty = true;
};

// Operand `index` (for messages) as an exact solid: coincident vertices
// merged, shells touching along edges split apart (then a Nef polyhedron,
// unless !options.exact_fallbacks: InputError), oriented outward. Throws
// InputError naming the operand when it is not closed or not a manifold.
Exact ToExact(const TriangleMesh& m, std::size_t index, const BooleanOptions& options);
// Appends e's triangles (points rounded to doubles) to out.
void AppendExact(const Exact& e, TriangleMesh& out);

// a op b corefined with exact predicates and constructions in doubles
// (Epick): taken when the result is closed and does not touch itself, else
// nullopt (float_corefinement.cc).
std::optional<SurfaceMesh> FloatCorefinement(BooleanOp op, const SurfaceMesh& a, const SurfaceMesh& b);
// a op b corefined with exact constructions (Epeck) into out; false with
// `why` set when corefinement gives no manifold result or an operand
// touches itself near the intersection (exact_corefinement.cc).
bool ExactCorefinement(BooleanOp op, const SurfaceMesh& a, const SurfaceMesh& b, SurfaceMesh& out, std::string& why);

// The Nef polyhedron of e (its own when it has one) (nef_boolean.cc).
std::shared_ptr<const NefSolid> NefOf(const Exact& e);
// a op b with Nef polyhedra: a surface mesh where the result is a
// 2-manifold, else the Nef polyhedron. Throws what CGAL throws.
Exact NefBoolean(BooleanOp op, const Exact& a, const Exact& b);
// Whether a surface mesh intersects itself (exact predicates; Nef polyhedra
// take only valid solids).
bool IntersectsItself(const SurfaceMesh& m);
// The number of facets of a Nef polyhedron.
std::size_t FaceCount(const NefSolid& nef);
// Appends a Nef polyhedron's facets, triangulated (points rounded to doubles).
void AppendNef(const NefSolid& nef, TriangleMesh& out);

// A closed mesh's convex parts, each as its vertices: the hull's when the
// mesh is convex, else CGAL's Nef convex decomposition (convex_parts.cc).
std::vector<std::vector<std::array<double, 3>>> ConvexParts(const TriangleMesh& m);

}  // namespace fabatlas::mesh::internal
