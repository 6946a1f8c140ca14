// MinkowskiSum (exact_boolean.h): the union of the convex hulls of the
// operands' convex parts' pairwise sums, as OpenSCAD 2021.01 computes it.
#include <array>
#include <utility>
#include <vector>

#include "exact_solid.h"
#include "fabatlas/mesh/exact_boolean.h"

namespace fabatlas::mesh {
namespace {

using ConvexPart = std::vector<std::array<double, 3>>;

}  // namespace

TriangleMesh MinkowskiSum(const std::vector<TriangleMesh>& operands, BooleanSummary* summary) {
  std::vector<ConvexPart> acc;
  bool first = true;
  for (const TriangleMesh& m : operands) {
    if (m.triangles.empty()) continue;
    std::vector<ConvexPart> parts = internal::ConvexParts(m);
    if (first) {
      acc = std::move(parts);
      first = false;
      continue;
    }
    std::vector<ConvexPart> sums;
    for (const ConvexPart& a : acc)
      for (const ConvexPart& b : parts) {
        ConvexPart s;
        s.reserve(a.size() * b.size());
        for (const auto& p : a)
          for (const auto& q : b) s.push_back({p[0] + q[0], p[1] + q[1], p[2] + q[2]});
        sums.push_back(ConvexHull(s).vertices);
      }
    acc = std::move(sums);
  }
  std::vector<TriangleMesh> hulls;
  for (const ConvexPart& part : acc) {
    TriangleMesh h = ConvexHull(part);
    if (!h.triangles.empty()) hulls.push_back(std::move(h));
  }
  if (hulls.size() == 1) return hulls[0];
  return ExactBoolean(BooleanOp::kUnion, hulls, summary);
}

}  // namespace fabatlas::mesh
