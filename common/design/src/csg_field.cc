// Signed distance bounds of CSG subtrees and their booleans (csg_field.h).
#include "csg_field.h"

#include <algorithm>

namespace fabatlas::design::csg {

void FieldProgram::Append(const Field& f) {
  const std::size_t i = nodes_.size();
  // A box leaf whose bounds are its box: outside it, its distance is the
  // box distance the cut would give (the same arithmetic), so it is
  // evaluated without the cut's test.
  const geometry::BoxDistance* box = f.parts.empty() ? f.leaf.target<geometry::BoxDistance>() : nullptr;
  if (box && !(box->lo == f.bounds.min && box->hi == f.bounds.max)) box = nullptr;
  nodes_.push_back(
      {f.bounds, f.parts.empty() ? &f.leaf : nullptr, box, f.op, static_cast<std::uint32_t>(f.parts.size()), 0});
  for (const auto& p : f.parts) Append(*p);
  nodes_[i].end = static_cast<std::uint32_t>(nodes_.size());
}

double FieldProgram::Evaluate(std::size_t i, double x, double y, double z) const {
  const Node& n = nodes_[i];
  double d = 0;
  std::size_t c = i + 1;
  for (std::uint32_t k = 0; k < n.parts; ++k, c = nodes_[c].end) {
    const Node& part = nodes_[c];
    double e;
    if (part.box) {
      e = (*part.box)(x, y, z);
    } else {
      // The distance to its box: a lower bound of the distance to anything in it.
      e = geometry::BoxDistance{part.bounds.min, part.bounds.max}(x, y, z);
      if (!(e >= band_)) e = part.leaf ? (*part.leaf)(x, y, z) : Evaluate(c, x, y, z);
    }
    if (k == 0)
      d = e;
    else if (n.op == Combine::kUnion)
      d = std::min(d, e);
    else if (n.op == Combine::kDifference)
      d = std::max(d, -e);
    else
      d = std::max(d, e);
  }
  return d;
}

std::shared_ptr<const Field> CombineFields(Combine op, std::vector<std::shared_ptr<const Field>> in) {
  std::vector<std::shared_ptr<const Field>> parts;
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (!in[i]) {
      if (op == Combine::kIntersection || (op == Combine::kDifference && i == 0)) return nullptr;
      continue;
    }
    parts.push_back(in[i]);
  }
  if (parts.empty()) return nullptr;
  if (parts.size() == 1) return parts[0];
  geometry::Box3 box = parts[0]->bounds;
  for (std::size_t i = 1; i < parts.size() && op != Combine::kDifference; ++i)
    for (int k = 0; k < 3; ++k) {
      if (op == Combine::kUnion) {
        box.min[k] = std::min(box.min[k], parts[i]->bounds.min[k]);
        box.max[k] = std::max(box.max[k], parts[i]->bounds.max[k]);
      } else {
        box.min[k] = std::max(box.min[k], parts[i]->bounds.min[k]);
        box.max[k] = std::min(box.max[k], parts[i]->bounds.max[k]);
      }
    }
  for (int k = 0; k < 3; ++k)
    if (box.min[k] > box.max[k]) return nullptr;  // an intersection of disjoint boxes
  auto field = std::make_shared<Field>();
  field->bounds = box;
  field->op = op;
  field->parts = std::move(parts);
  return field;
}

}  // namespace fabatlas::design::csg
