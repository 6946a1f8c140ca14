// evaluate_model/csg_node.h (internal to fabatlas_scad) — the CSG tree evaluate_model.h's
// evaluator builds, and its text as OpenSCAD 2021.01's .csg export.
#pragma once

#include <string>
#include <vector>

namespace fabatlas::scad::internal {

// A node of the CSG tree: its head (`cube(size = [1, 1, 1], center = false)`)
// and children.
struct CsgOut {
  std::string head{};
  std::vector<CsgOut> children{};
  std::string modifier{};  // "%" or "#", written before the indentation as OpenSCAD does
};

// Appends node n at `depth` (tabs) and its children to out.
void Print(const CsgOut& n, int depth, std::string& out);

}  // namespace fabatlas::scad::internal
