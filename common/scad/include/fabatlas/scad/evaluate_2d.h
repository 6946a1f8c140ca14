// fabatlas/scad/evaluate_2d.h — OpenSCAD 2021.01's 2-D geometry and its
// extrusions, evaluated exactly as OpenSCAD evaluates them: every 2-D
// boolean, offset and minkowski through Clipper 6.4.2 (Johnson, "Clipper",
// docs/references.md) on OpenSCAD's integer grid (coordinates times 2^16,
// truncated toward zero), hull by a convex hull of the children's vertices,
// linear_extrude and rotate_extrude as the closed triangle meshes OpenSCAD
// builds (its slice and fragment counts, its quad split). Millimetres,
// degrees. Single-threaded; each call is independent (thread-safe).
#pragma once

#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "fabatlas/mesh/triangle_mesh.h"
#include "fabatlas/scad/csg_tree.h"
#include "fabatlas/scad/primitive_mesh.h"

namespace fabatlas::scad {

// OpenSCAD's 2-D result: simple loops that do not cross (they may touch at
// a vertex), outer boundaries counter-clockwise, holes clockwise. Empty for
// an empty shape.
struct Polygon2d {
  std::vector<Loop> loops;
};

// A node of the subtree has no native equivalent here and no callback of
// Evaluate2dOptions can supply it (e.g. text without `outline`, linear_extrude
// of a DXF file). what() names the node and its .csg line.
class NoNativeEquivalentError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Evaluate2dOptions {
  // The closed mesh of a 3-D child (projection's children), in the child's
  // own coordinates. Required for projection; without it projection throws
  // NoNativeEquivalentError.
  std::function<mesh::TriangleMesh(const CsgNode& child)> mesh3d;
  // The outline of a 2-D subtree with no native equivalent (text(...),
  // import of a .dxf or .svg): loops filled by the even-odd rule, e.g.
  // OpenSCAD's own SVG export of that subtree (svg_outline.h). Throws when it
  // has none. Without it such nodes throw NoNativeEquivalentError.
  std::function<std::vector<Loop>(const CsgNode& node)> outline;
  // import("x.dxf" / "x.svg") resolves a relative file below this directory;
  // a file outside it is refused (fabatlas::InputError) before `outline` is
  // asked.
  std::filesystem::path model_dir;
};

// The dimension of a subtree's geometry as OpenSCAD decides it: 2 for
// circle, square, polygon, text, offset, projection and import of .dxf/.svg;
// 3 for cube, sphere, cylinder, polyhedron, the extrusions, surface and other
// imports; for any other node the dimension of its first child that has one;
// 0 for a subtree with no geometry (an empty group).
int Dimension(const CsgNode& node);

// A 2-D subtree (circle, square, polygon with paths, multmatrix, group /
// union / difference / intersection / render / color, offset(r | delta,
// chamfer), hull, minkowski, resize, projection(cut = true | false) through
// options.mesh3d, text and 2-D imports through options.outline) as OpenSCAD
// 2021.01 computes it. Appends OpenSCAD's warnings, worded as OpenSCAD
// words them ("Ignoring 3D child object for 2D operation", "Unable to convert
// points[1] = ... to a vec2 of numbers", ...), to *warnings (may be null).
// Throws NoNativeEquivalentError as documented above.
Polygon2d Evaluate2d(const CsgNode& node, const Evaluate2dOptions& options, std::vector<std::string>* warnings);

// linear_extrude(height, center, twist, slices, scale) of the node's 2-D
// children (their union): OpenSCAD 2021.01's slice count when `slices` is
// absent (primitive_mesh.h ExtrudeSlices), each side quad split as it splits
// them, caps triangulating the polygon with its holes, a top scaled to zero
// collapsed to its point or segment. A closed, outward (counter-clockwise
// seen from outside) triangle mesh without degenerate triangles; empty for
// an empty polygon or height <= 0. Not a 2-manifold only where OpenSCAD's
// solid is not one either: loops of a top scaled to zero collapsing onto the
// same segment or point (a square with a hole under scale = [0, 1]).
mesh::TriangleMesh LinearExtrude(const CsgNode& linear_extrude_node, const Evaluate2dOptions& options,
                                 std::vector<std::string>* warnings);

// rotate_extrude(angle, $fn, $fa, $fs) of the node's 2-D children (their
// union) about z: the polygon's y becomes z, OpenSCAD 2021.01's fragment
// count (from the polygon's x extent, times |angle| / 360), a full turn
// starting on -x, a partial one (|angle| < 360, OpenSCAD's range (-360, 360])
// starting on +x with caps at both ends. Vertices on the axis are shared by
// all fragments. A polygon with points on both sides of the axis gives an
// empty mesh and OpenSCAD's error line in *warnings, as OpenSCAD does.
// Closed and outward as LinearExtrude; a polygon touching the axis at a
// single vertex pinches there (one vertex of two sheets), as OpenSCAD's.
mesh::TriangleMesh RotateExtrude(const CsgNode& rotate_extrude_node, const Evaluate2dOptions& options,
                                 std::vector<std::string>* warnings);

}  // namespace fabatlas::scad
