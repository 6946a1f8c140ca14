// The .csg text of a CSG tree (csg_node.h).
#include "csg_node.h"

namespace fabatlas::scad::internal {

void Print(const CsgOut& n, int depth, std::string& out) {
  out += n.modifier;
  out.append(depth, '\t');
  out += n.head;
  if (n.children.empty()) {
    out += ";\n";
    return;
  }
  out += " {\n";
  for (const CsgOut& c : n.children) Print(c, depth + 1, out);
  out.append(depth, '\t');
  out += "}\n";
}

}  // namespace fabatlas::scad::internal
