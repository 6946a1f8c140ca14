// fabatlas/scad/surface_mesh.h — OpenSCAD's `surface()`: a height map read
// from a DAT text file or a PNG image, as the closed polygon mesh OpenSCAD
// 2021.01 builds of it. Millimetres (one grid step is 1 mm).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::scad {

// The heights of a surface: `rows` x `columns`, row-major; row r lies at
// y = r, column c at x = c (before centring).
struct HeightMap {
  int rows = 0;
  int columns = 0;
  std::vector<double> heights;
  // The floor of the solid: min(0, lowest height read - 1). Values a short
  // DAT row lacks are 0 but do not lower the floor (as in OpenSCAD).
  double floor = 0;
};

// Reads `file` as OpenSCAD reads a surface: a PNG (by its signature) gives
// one row per image row, bottom row first, each pixel's height
// 100 / 255 * (0.2126 R + 0.7152 G + 0.0722 B) (with `invert`,
// 100 / 255 * (1 - that), as OpenSCAD 2021.01 computes it); anything else is
// DAT text: rows of numbers separated by spaces or tabs, lines starting with
// '#' and blank lines skipped, reading stopping at the first value that is
// not a number (with a warning); a short row's missing values are 0. A file
// that cannot be read gives an empty map and a warning, as OpenSCAD warns.
HeightMap ReadHeightMap(const std::filesystem::path& file, bool invert, std::vector<std::string>* warnings);

// The closed mesh of a height map, outward-facing: per grid cell four
// triangles meeting at the cell's centre (at the mean of its corners'
// heights), walls down to `map.floor`, and the floor.
// With `center` the grid is centred on the origin in x and y. Empty when the
// map has fewer than 2 rows or 2 columns (OpenSCAD's surface is then empty).
mesh::TriangleMesh SurfaceMesh(const HeightMap& map, bool center);

}  // namespace fabatlas::scad
