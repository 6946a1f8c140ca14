// fabatlas/scad/primitive_mesh.h — OpenSCAD's primitives as the polygon
// meshes OpenSCAD itself builds (faceting by $fn, $fa, $fs), so a level set
// of them encloses the volume of OpenSCAD's own STL. Millimetres, degrees.
// Each function returns a closed triangle mesh (orientation unspecified:
// level sets are signed by their own flood fill).
#pragma once

#include <array>
#include <vector>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::scad {

using Point2 = std::array<double, 2>;
using Loop = std::vector<Point2>;  // a closed polygon, last point != first

// OpenSCAD's number of fragments of a circle of radius r: $fn when > 0 (at
// least 3), else ceil(max(min(360 / $fa, 2 pi r / $fs), 5)); 3 below r ~ 1e-6.
int Fragments(double r, double fn, double fs, double fa);

mesh::TriangleMesh CubeMesh(const std::array<double, 3>& size, bool center);
mesh::TriangleMesh SphereMesh(double r, int fragments);
mesh::TriangleMesh CylinderMesh(double h, double r1, double r2, bool center, int fragments);
// Polygon faces (any size >= 3, fan-triangulated as OpenSCAD's convex faces).
mesh::TriangleMesh PolyhedronMesh(const std::vector<std::array<double, 3>>& points,
                                  const std::vector<std::vector<int>>& faces);

// 2D: a circle as OpenSCAD's regular polygon; a square.
Loop CircleLoop(double r, int fragments);
Loop SquareLoop(double x, double y, bool center);

// Triangles (index triples into `loop`) of a simple polygon by ear clipping.
std::vector<std::array<int, 3>> TriangulateLoop(const Loop& loop);

// linear_extrude of one simple loop: z from 0 (or -h/2 with center) to h,
// rotated by -twist degrees and scaled by `scale` (x, y) at the top, with
// `slices` layers between.
mesh::TriangleMesh LinearExtrudeMesh(const Loop& loop, double height, bool center, double twist, int slices,
                                     const Point2& scale);
// rotate_extrude of one simple loop in the (x >= 0, y) half-plane about z,
// through `angle` degrees (360 = closed) in `fragments` steps.
mesh::TriangleMesh RotateExtrudeMesh(const Loop& loop, double angle, int fragments);

}  // namespace fabatlas::scad
