// Reading the arguments of OpenSCAD's CSG nodes (csg_arguments.h).
#include "csg_arguments.h"

#include "fabatlas/scad/primitive_mesh.h"

namespace fabatlas::design::csg {

bool IsTwoD(const std::string& name) {
  return name == "circle" || name == "square" || name == "polygon" || name == "text" || name == "offset" ||
         name == "projection";
}

bool IsThreeD(const std::string& name) {
  return name == "cube" || name == "sphere" || name == "cylinder" || name == "polyhedron" || name == "linear_extrude" ||
         name == "rotate_extrude" || name == "surface";
}

double Num(const CsgValue& v, double fallback) { return v.type == CsgValue::Type::kNumber ? v.number : fallback; }

std::vector<double> Numbers(const CsgValue& v) {
  std::vector<double> out;
  for (const auto& x : v.items) out.push_back(Num(x, 0));
  return out;
}

int FragmentsOf(const CsgNode& n, double r) {
  return scad::Fragments(r, n.Number("$fn", 0), n.Number("$fs", 2), n.Number("$fa", 12));
}

}  // namespace fabatlas::design::csg
