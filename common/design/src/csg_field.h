// Internal: signed distance bounds of CSG subtrees not sampled yet (convex
// primitives, prisms and booleans of them), so a whole tree of such nodes is
// sampled once, for the level-set road of the `openscad` node
// (openscad_node.h).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "fabatlas/geometry/convex_mesh_distance.h"
#include "fabatlas/geometry/solid.h"

namespace fabatlas::design::csg {

enum class Combine { kUnion, kDifference, kIntersection };

// A subtree's signed distance bound not sampled yet: exact within `band` of
// its surface (the band of the grid it will be sampled on), beyond it a
// lower bound in magnitude (as geometry::FromDistance requires); `bounds` is
// its material's bounding box. A convex primitive or a prism is its distance
// function (`leaf`); a boolean of such subtrees is `op` over its `parts`
// (two or more, `leaf` empty), evaluated by FieldProgram.
struct Field {
  geometry::Box3 bounds;
  geometry::DistanceFunction leaf;
  Combine op = Combine::kUnion;
  std::vector<std::shared_ptr<const Field>> parts;
};

// The booleans of fields as OpenVDB's CSG combines level sets (min for
// union, max(a, -b) for difference, max for intersection: the same voxel
// values in the band). An operand whose box lies `band` or farther from p
// contributes its box distance without being evaluated: that leaves every
// value within the band exact and every value beyond it a bound.
//
// A field's tree is laid out once per sampling as an array in pre-order (a
// boolean followed by its operands' subtrees) and evaluated per point by one
// recursive function over it: no std::function call per boolean and no
// pointer chase per operand, only one per primitive other than a box (a
// box's distance is called directly). The same floating-point
// operations in the same order as the tree they come from, so the same
// values to the bit. Thread-safe (it only reads); `root` must outlive it.
class FieldProgram {
 public:
  // root: a boolean (a field with parts).
  FieldProgram(const Field& root, double band) : band_(band) { Append(root); }

  double operator()(double x, double y, double z) const { return Evaluate(0, x, y, z); }

 private:
  struct Node {
    geometry::Box3 bounds;
    const geometry::DistanceFunction* leaf;  // null for a boolean
    const geometry::BoxDistance* box;        // a box leaf's own function, called directly
    Combine op;
    std::uint32_t parts;  // a boolean's operands, the subtrees after it
    std::uint32_t end;    // one past this node's subtree
  };

  void Append(const Field& f);

  // Boolean node i: its operands in order, each its box distance where that
  // is `band` or more, else its own value (a primitive's or a boolean's).
  double Evaluate(std::size_t i, double x, double y, double z) const;

  std::vector<Node> nodes_;
  double band_;
};

// The boolean `op` of fields (FieldProgram evaluates it); nullptr: no
// material.
std::shared_ptr<const Field> CombineFields(Combine op, std::vector<std::shared_ptr<const Field>> in);

}  // namespace fabatlas::design::csg
