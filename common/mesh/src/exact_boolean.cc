// Exact mesh booleans (see exact_boolean.h): the order of the steps. Each
// pair of operands is corefined in doubles (float_corefinement.cc), then
// with exact constructions (exact_corefinement.cc), then with Nef polyhedra
// (nef_boolean.cc); exact_solid.h lists the files.
#include "fabatlas/mesh/exact_boolean.h"

#include <CGAL/Polygon_mesh_processing/bbox.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <numeric>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "exact_solid.h"
#include "fabatlas/error.h"

namespace fabatlas::mesh {
namespace {

using internal::Exact;
using internal::SurfaceMesh;
namespace PMP = CGAL::Polygon_mesh_processing;

bool Meet(const CGAL::Bbox_3& a, const CGAL::Bbox_3& b) { return CGAL::do_overlap(a, b); }

// a op b, both non-empty: corefinement (in doubles, then exact), else Nef.
Exact Apply(BooleanOp op, const Exact& a, const Exact& b, std::size_t b_index, const BooleanOptions& options,
            BooleanSummary& summary) {
  std::string why;
  if (!a.nef && !b.nef) {
    if (std::optional<SurfaceMesh> fast = internal::FloatCorefinement(op, a.mesh, b.mesh)) {
      ++summary.corefinements;
      Exact r;
      r.empty = fast->number_of_faces() == 0;
      if (!r.empty) r.box = PMP::bbox(*fast);
      r.mesh = std::move(*fast);
      return r;
    }
    if (!options.exact_fallbacks)
      throw InputError(std::string("exact ") + BooleanOpName(op) + " needs exact constructions");
    ++summary.exact_corefinements;
    SurfaceMesh out;
    const bool ok = internal::ExactCorefinement(op, a.mesh, b.mesh, out, why);
    ++summary.corefinements;
    if (ok) {
      Exact r;
      r.empty = out.number_of_faces() == 0;
      if (!r.empty) r.box = PMP::bbox(out);
      r.mesh = std::move(out);
      return r;
    }
  } else {
    why = "an operand is not a 2-manifold";
  }
  if (!options.exact_fallbacks)
    throw InputError(std::string("exact ") + BooleanOpName(op) + " needs Nef polyhedra (" + why + ")");
  ++summary.nef;
  if (summary.nef_why.empty()) summary.nef_why = why;
  // Nef polyhedra take only valid solids (CGAL does not check: a mesh that
  // touches itself can crash the construction).
  for (const Exact* e : {&b, &a})
    if (!e->nef && internal::IntersectsItself(e->mesh))
      throw InputError("exact boolean operand " + (e == &b ? std::to_string(b_index) : std::string("0")) +
                       (e == &a && b_index > 1 ? " (with the operands before " + std::to_string(b_index) + ")" : "") +
                       " intersects itself (" + BooleanOpName(op) + ": " + why + ")");
  try {
    return internal::NefBoolean(op, a, b);
  } catch (const std::exception& e) {
    throw InputError(std::string("exact ") + BooleanOpName(op) + " could not be computed (" + why +
                     "; Nef polyhedra: " + e.what() + ")");
  }
}

// Groups of operands whose bounding boxes meet, transitively.
std::vector<std::vector<std::size_t>> TouchingGroups(const std::vector<Exact>& in) {
  std::vector<std::size_t> parent(in.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (std::size_t i = 0; i < in.size(); ++i)
    for (std::size_t j = i + 1; j < in.size(); ++j)
      if (Meet(in[i].box, in[j].box)) parent[find(j)] = find(i);
  std::map<std::size_t, std::vector<std::size_t>> groups;
  for (std::size_t i = 0; i < in.size(); ++i) groups[find(i)].push_back(i);
  std::vector<std::vector<std::size_t>> out;
  for (auto& [_, g] : groups) out.push_back(std::move(g));
  return out;
}

std::size_t FaceCount(const Exact& e) {
  if (e.empty) return 0;
  return e.nef ? internal::FaceCount(*e.nef) : e.mesh.number_of_faces();
}

// The union of operands whose bounding boxes meet transitively (index: each
// one's index among the boolean's operands, for messages), as pieces whose
// boxes are apart. The two smallest operands (by faces) whose boxes meet are
// joined first, and the result goes back among the operands, as Manifold
// orders a union's operands by size: a corefinement costs about the faces
// of both operands, so small operands meet each other before they meet a
// large one, which is not rebuilt once per operand of the node (issue1069
// of OpenSCAD's corpus, a Minkowski sum's union of 24 hulls: 2.3x less
// time). An operand whose box meets no other piece's is a piece of the
// result as it is.
std::vector<Exact> UnionOfTouching(std::vector<Exact> pieces, std::vector<std::size_t> index,
                                   const BooleanOptions& options, BooleanSummary& summary) {
  std::vector<Exact> done;
  while (!pieces.empty()) {
    std::size_t smallest = 0;
    for (std::size_t k = 1; k < pieces.size(); ++k)
      if (FaceCount(pieces[k]) < FaceCount(pieces[smallest])) smallest = k;
    std::optional<std::size_t> partner;
    for (std::size_t k = 0; k < pieces.size(); ++k)
      if (k != smallest && Meet(pieces[smallest].box, pieces[k].box) &&
          (!partner || FaceCount(pieces[k]) < FaceCount(pieces[*partner])))
        partner = k;
    if (!partner) {  // apart from every other piece, and from all they will join into
      done.push_back(std::move(pieces[smallest]));
      pieces.erase(pieces.begin() + static_cast<std::ptrdiff_t>(smallest));
      index.erase(index.begin() + static_cast<std::ptrdiff_t>(smallest));
      continue;
    }
    // The earlier operand first, as the operands were given.
    const std::size_t first = index[smallest] < index[*partner] ? smallest : *partner;
    const std::size_t second = first == smallest ? *partner : smallest;
    Exact joined = Apply(BooleanOp::kUnion, pieces[first], pieces[second], index[second], options, summary);
    index[first] = std::min(index[first], index[second]);
    pieces[first] = std::move(joined);
    pieces.erase(pieces.begin() + static_cast<std::ptrdiff_t>(second));
    index.erase(index.begin() + static_cast<std::ptrdiff_t>(second));
  }
  return done;
}

// The same mesh with its vertices sorted by coordinates and its triangles
// by their vertices (each starting at its least, orientation kept): CGAL
// lists a result's vertices and faces in an order that depends on the
// addresses of its internal boxes (Box_intersection_d's ids), so equal
// results came out in different orders between runs, and sums over them
// (volumes, ΔG, the level set built from them) differed in the last bits.
TriangleMesh Canonical(TriangleMesh m) {
  std::vector<std::int32_t> order(m.vertices.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) { return m.vertices[a] < m.vertices[b]; });
  std::vector<std::int32_t> rank(m.vertices.size());
  TriangleMesh out;
  out.vertices.reserve(m.vertices.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    rank[order[i]] = static_cast<std::int32_t>(i);
    out.vertices.push_back(m.vertices[order[i]]);
  }
  out.triangles.reserve(m.triangles.size());
  for (const auto& t : m.triangles) {
    std::array<std::int32_t, 3> r{rank[t[0]], rank[t[1]], rank[t[2]]};
    const int k = r[0] <= r[1] && r[0] <= r[2] ? 0 : r[1] <= r[2] ? 1 : 2;
    out.triangles.push_back({r[k], r[(k + 1) % 3], r[(k + 2) % 3]});
  }
  std::sort(out.triangles.begin(), out.triangles.end());
  return out;
}

}  // namespace

const char* BooleanOpName(BooleanOp op) {
  switch (op) {
    case BooleanOp::kUnion:
      return "union";
    case BooleanOp::kDifference:
      return "difference";
    case BooleanOp::kIntersection:
      return "intersection";
  }
  return "union";
}

namespace {
TriangleMesh UnorderedBoolean(BooleanOp op, const std::vector<TriangleMesh>& operands, BooleanSummary* summary_out,
                              const BooleanOptions& options);
}  // namespace

TriangleMesh ExactBoolean(BooleanOp op, const std::vector<TriangleMesh>& operands, BooleanSummary* summary_out,
                          const BooleanOptions& options) {
  return Canonical(UnorderedBoolean(op, operands, summary_out, options));
}

namespace {
// The union of the operands `in`: operands apart from all others join the
// result as they are; each group of touching ones is united (UnionOfTouching).
TriangleMesh UnionAll(std::vector<Exact>& in, const BooleanOptions& options, BooleanSummary& summary) {
  TriangleMesh out;
  std::vector<Exact> present;
  std::vector<std::size_t> present_index;  // each one's index among the operands
  for (std::size_t i = 0; i < in.size(); ++i)
    if (!in[i].empty) {
      present.push_back(std::move(in[i]));
      present_index.push_back(i);
    }
  // Operands apart from all others join the result as they are.
  for (const auto& group : TouchingGroups(present)) {
    summary.disjoint += group.size() == 1 && present.size() > 1;
    std::vector<Exact> pieces;
    std::vector<std::size_t> pieces_index;
    for (std::size_t k : group) {
      pieces.push_back(std::move(present[k]));
      pieces_index.push_back(present_index[k]);
    }
    for (const Exact& piece : UnionOfTouching(std::move(pieces), pieces_index, options, summary))
      internal::AppendExact(piece, out);
  }
  return out;
}

// The operands taken away (`away`, their operand indices `away_index`),
// joined into one when every piece of their union is a surface mesh (apart
// pieces side by side in one mesh); left as they are otherwise.
void JoinSubtrahends(std::vector<Exact>& away, std::vector<std::size_t>& away_index, const BooleanOptions& options,
                     BooleanSummary& summary) {
  std::vector<Exact> pieces;
  for (const auto& group : TouchingGroups(away)) {
    std::vector<Exact> members;
    std::vector<std::size_t> members_index;
    for (std::size_t k : group) {
      members.push_back(away[k]);
      members_index.push_back(away_index[k]);
    }
    for (Exact& piece : UnionOfTouching(std::move(members), members_index, options, summary))
      pieces.push_back(std::move(piece));
  }
  if (std::none_of(pieces.begin(), pieces.end(), [](const Exact& e) { return e.nef != nullptr; })) {
    Exact joined = std::move(pieces[0]);
    for (std::size_t k = 1; k < pieces.size(); ++k) {
      joined.mesh += pieces[k].mesh;
      joined.box += pieces[k].box;
    }
    away.clear();
    away.push_back(std::move(joined));
    away_index.resize(1);
  }
}

// in[0] minus the other operands (in[0] not empty).
// a - b1 - b2 - ... = a - (b1 | b2 | ...): the operands taken away are
// joined first (apart ones cost nothing) and taken away at once, so the
// first operand is corefined once, not once per operand (camera-tests of
// OpenSCAD's corpus, a sphere minus three crossing cylinders: 8-10x
// less time). Where a piece of their union is a Nef polyhedron, one
// operand at a time.
TriangleMesh DifferenceAll(std::vector<Exact>& in, const BooleanOptions& options, BooleanSummary& summary) {
  TriangleMesh out;
  Exact acc = std::move(in[0]);
  std::vector<Exact> away;
  std::vector<std::size_t> away_index;
  for (std::size_t i = 1; i < in.size(); ++i) {
    if (in[i].empty || !Meet(acc.box, in[i].box)) {
      ++summary.disjoint;
      continue;  // nothing to take away
    }
    away.push_back(std::move(in[i]));
    away_index.push_back(i);
  }
  if (away.size() > 1) JoinSubtrahends(away, away_index, options, summary);
  for (std::size_t k = 0; k < away.size() && !acc.empty; ++k)
    acc = Apply(BooleanOp::kDifference, acc, away[k], away_index[k], options, summary);
  internal::AppendExact(acc, out);
  return out;
}

TriangleMesh UnorderedBoolean(BooleanOp op, const std::vector<TriangleMesh>& operands, BooleanSummary* summary_out,
                              const BooleanOptions& options) {
  BooleanSummary local;
  BooleanSummary& summary = summary_out ? *summary_out : local;
  std::vector<Exact> in;
  in.reserve(operands.size());
  for (std::size_t i = 0; i < operands.size(); ++i) in.push_back(internal::ToExact(operands[i], i, options));
  TriangleMesh out;
  if (in.empty()) return out;
  if (op == BooleanOp::kUnion) return UnionAll(in, options, summary);
  if (op == BooleanOp::kDifference && !in[0].empty) return DifferenceAll(in, options, summary);
  Exact acc = std::move(in[0]);
  for (std::size_t i = 1; i < in.size() && !acc.empty; ++i) {
    if (in[i].empty || !Meet(acc.box, in[i].box)) {
      ++summary.disjoint;
      if (op == BooleanOp::kIntersection) return out;  // nothing in common
      continue;                                        // nothing to take away
    }
    acc = Apply(op, acc, in[i], i, options, summary);
  }
  internal::AppendExact(acc, out);
  return out;
}

}  // namespace

}  // namespace fabatlas::mesh
