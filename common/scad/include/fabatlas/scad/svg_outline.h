// fabatlas/scad/svg_outline.h — a 2D shape as OpenSCAD 2021.01 exports it to
// SVG (`openscad -o shape.svg`): one <path> whose `d` is closed polylines
// "M x,y L x,y ... z", y pointing down. Read back as loops in OpenSCAD's own
// coordinates (y up), to be filled by the even-odd rule.
#pragma once

#include <string>
#include <vector>

#include "fabatlas/scad/primitive_mesh.h"

namespace fabatlas::scad {

// Throws fabatlas::InputError naming `file` for a path command other than
// M, L and z, or a coordinate that is not a number. An SVG without a path
// (an empty shape) gives no loops.
std::vector<Loop> ReadSvgOutline(const std::string& svg_text, const std::string& file);

}  // namespace fabatlas::scad
