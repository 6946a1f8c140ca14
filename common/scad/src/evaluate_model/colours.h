// evaluate_model/colours.h (internal to fabatlas_scad) — the colours OpenSCAD
// 2021.01's color() takes by name.
#pragma once

#include <string>

namespace fabatlas::scad::internal {

// The colour keywords OpenSCAD 2021.01 knows (SVG 1.1 / CSS3 colour keywords,
// red, green, blue of 0-255, alpha), any case, and "#rgb", "#rgba",
// "#rrggbb", "#rrggbbaa", as red, green, blue, alpha in [0, 1]; false for
// any other name (rgba untouched then).
bool ColourByName(std::string name, double rgba[4]);

// What an unknown name is told: color("NAME"): unknown colour name (...).
std::string UnknownColourText(const std::string& name);

}  // namespace fabatlas::scad::internal
