// fabatlas/scad/primitive_mesh.h — OpenSCAD's primitives as the polygon
// meshes OpenSCAD itself builds (faceting by $fn, $fa, $fs), so a level set
// of them encloses the volume of OpenSCAD's own STL. Millimetres, degrees.
// Each function returns a closed triangle mesh; cube, sphere and cylinder
// face outward (the mesh road's volume is their signed volume), a
// polyhedron keeps its faces' winding.
#pragma once

#include <array>
#include <vector>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::scad {

using Point2 = std::array<double, 2>;
using Loop = std::vector<Point2>;  // a closed polygon, last point != first

// Sine and cosine of an angle in degrees as OpenSCAD 2021.01 computes them:
// exact at multiples of 30 and 45 degrees (sin 30 = 0.5, sin 180 = 0), so
// its circles have exact axis points. NaN for a non-finite angle.
double SinDegrees(double degrees);
double CosDegrees(double degrees);

// OpenSCAD's number of fragments of a circle of radius r: $fn when > 0 (at
// least 3), else ceil(max(min(360 / $fa, 2 pi r / $fs), 5)); 3 below r ~ 1e-6
// and for a non-finite $fn.
int Fragments(double r, double fn, double fs, double fa);

mesh::TriangleMesh CubeMesh(const std::array<double, 3>& size, bool center);
mesh::TriangleMesh SphereMesh(double r, int fragments);
mesh::TriangleMesh CylinderMesh(double h, double r1, double r2, bool center, int fragments);
// Polygon faces (any size >= 3, fan-triangulated as OpenSCAD's convex faces).
mesh::TriangleMesh PolyhedronMesh(const std::vector<std::array<double, 3>>& points,
                                  const std::vector<std::vector<int>>& faces);

// OpenSCAD 2021.01's test before it turns a polyhedron into a Nef
// polyhedron: true when `m` (outward, triangles) is closed, each directed
// edge used once, connected, and no edge folds inward by 0.1 degrees or
// more. OpenSCAD then takes the convex hull of its points instead, so a
// polyhedron whose non-planar faces fold slightly inward renders as its
// hull (issue1867.scad).
bool ApproximatelyConvex(const mesh::TriangleMesh& m);

// 2D: a circle as OpenSCAD's regular polygon; a square.
Loop CircleLoop(double r, int fragments);
Loop SquareLoop(double x, double y, bool center);

// Triangles (index triples into `loop`) of a simple polygon by ear clipping.
std::vector<std::array<int, 3>> TriangulateLoop(const Loop& loop);

// A region of the plane: its triangles (counter-clockwise, indices into
// `points`) and its boundary loops (indices into `points`), each with the
// region on its left: outer loops counter-clockwise, holes clockwise, as
// OpenSCAD's outlines. Boundary loops have no collinear vertices (OpenSCAD's
// 2D booleans drop them); triangles may use those vertices (the cap then has
// a vertex on a boundary edge, which encloses the same solid).
struct Region2 {
  std::vector<Point2> points;
  std::vector<std::array<int, 3>> triangles;
  std::vector<std::vector<int>> loops;
};

// linear_extrude of a region (region_outline.h builds one from OpenSCAD's
// 2D children): z from 0 (or -h/2 with center) to h, rotated by -twist
// degrees and scaled by `scale` (x, y, each >= 0) at the top, with `slices`
// layers between. Each side quad is split along its shorter diagonal
// (lengths within 10 ppm are equal; then by the twist's sign, zero counting
// as negative, and whether the loop is a hole), as OpenSCAD 2021.01 splits
// them: the diagonal decides the volume of a twisted wall (a 300 mm^2 cross
// twisted 57.5 degrees in 5 slices: 5525 or 6194 mm^3). A top scaled to
// zero in x or y has no cap, its coinciding vertices merged and its quads
// split along the other diagonal, as OpenSCAD's. Closed and outward, no
// degenerate triangles.
mesh::TriangleMesh LinearExtrudeMesh(const Region2& region, double height, bool center, double twist, int slices,
                                     const Point2& scale);

// OpenSCAD 2021.01's number of slices of a linear_extrude without a
// `slices` argument, from the largest squared distance of the outline's
// vertices to the origin (r_sqr) and the largest squared distance a vertex
// moves by the scale (delta_sqr): 1 without twist and with uniform scale;
// with twist at least twist / 120 degrees, $fn * twist / 360 when $fn > 0,
// else the fewer of twist / $fa and the vertex path's length / $fs (a
// helix, a conical spiral with uniform scale); without twist but with
// non-uniform scale, $fn or the diagonal path's length / $fs.
int ExtrudeSlices(double r_sqr, double delta_sqr, double height, double twist, const Point2& scale, double fn,
                  double fs, double fa);
// rotate_extrude of a region in one half-plane (x >= 0 or x <= 0, its y
// becoming z) about z, through `angle` degrees in `fragments` steps, each
// ring at OpenSCAD 2021.01's angles: a closed one (|angle| >= 360) starts on
// -x (so an odd number of fragments puts a vertex on -x, not +x), a partial
// one starts on +x and has the region's triangles as its end caps. A point
// on the axis is one vertex shared by every ring. Closed and outward.
mesh::TriangleMesh RotateExtrudeMesh(const Region2& region, double angle, int fragments);
// The same of one simple loop.
mesh::TriangleMesh RotateExtrudeMesh(const Loop& loop, double angle, int fragments);

}  // namespace fabatlas::scad
