// fabatlas/scad/part_trees.h — a model's parts (its top-level bodies and
// their colour regions) as CSG programs of their own, so each is evaluated
// apart while the model's solid stays the union (docs/openscad.md, "Parts and
// colours").
#pragma once

#include <array>
#include <string>
#include <vector>

#include "fabatlas/scad/csg_tree.h"

namespace fabatlas::scad {

// One part: the material of one top-level statement of the model (a body)
// that carries one colour.
struct PartTree {
  int body = 0;                  // 1-based index of the top-level statement
  bool coloured = false;         // false: no color() applies (OpenSCAD's default colour)
  std::array<double, 4> rgba{};  // red, green, blue, alpha in [0, 1], as the .csg writes color()
  // The part as a CSG program in canonical syntax (CsgNode::canonical
  // pieces): evaluating it gives the part's material. Parts may overlap
  // (a red and a blue cube unioned); the caller decides who keeps the overlap.
  std::string csg;
};

// The parts of `root` (ParseCsg's result: a group of the top-level
// statements), in order: body by body, and within a body colour by colour
// in the order the colours first appear. OpenSCAD's colour rules (User
// Manual, "color"): the innermost color() wins; a union (group, union,
// render, color) keeps each child's colour; a difference or intersection
// takes its first child's colours, each region cut or trimmed by the other
// children; any other operation (hull, minkowski, an extrusion, resize, a
// primitive) is one region coloured by the first color() inside it, else by
// the colour around it. A color() that OpenSCAD could not parse (written as
// [-1, -1, -1, 1]) leaves the colour around it.
std::vector<PartTree> PartTrees(const CsgNode& root);

// "#rrggbb", with "aa" appended when alpha < 1 (components rounded to 0-255).
std::string HexColour(const std::array<double, 4>& rgba);

}  // namespace fabatlas::scad
