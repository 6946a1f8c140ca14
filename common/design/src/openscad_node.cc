// The `openscad` node: OpenSCAD's CSG tree evaluated with level sets
// (openscad_node.h, docs/openscad.md).
#include "openscad_node.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <utility>

#include "convex_hull_2d.h"
#include "fabatlas/error.h"
#include "fabatlas/stopwatch.h"
#include "fabatlas/mesh/enclosed_volume.h"
#include "fabatlas/mesh/exact_boolean.h"
#include "fabatlas/mesh/read_mesh.h"
#include "fabatlas/geometry/convex_mesh_distance.h"
#include "fabatlas/scad/csg_tree.h"
#include "fabatlas/scad/customizer.h"
#include "fabatlas/scad/evaluate_2d.h"
#include "fabatlas/scad/evaluate_model.h"
#include "fabatlas/scad/model_files.h"
#include "fabatlas/scad/part_trees.h"
#include "fabatlas/scad/primitive_mesh.h"
#include "fabatlas/scad/surface_mesh.h"
#include "fabatlas/scad/region_distance.h"
#include "fabatlas/scad/region_outline.h"
#include "fabatlas/scad/svg_outline.h"
#include "fabatlas/sha256.h"

namespace fabatlas::design {
namespace {

namespace fs = std::filesystem;
using geometry::Solid;
using scad::CsgNode;
using scad::CsgValue;
using scad::Loop;

// An affine map x -> A x + t, row-major 3x4.
using Affine = std::array<double, 12>;
constexpr Affine kIdentity = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

Affine Compose(const Affine& a, const Affine& b) {  // a after b
  Affine c{};
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) c[4 * r + k] = a[4 * r] * b[k] + a[4 * r + 1] * b[4 + k] + a[4 * r + 2] * b[8 + k];
    c[4 * r + 3] = a[4 * r] * b[3] + a[4 * r + 1] * b[7] + a[4 * r + 2] * b[11] + a[4 * r + 3];
  }
  return c;
}

std::string AffineText(const Affine& a) {
  std::string s;
  for (double v : a) s += scad::FormatScadNumber(v) + ",";
  return s;
}

void Transform(mesh::TriangleMesh& m, const Affine& a) {
  for (auto& v : m.vertices) {
    const double x = v[0], y = v[1], z = v[2];
    v = {a[0] * x + a[1] * y + a[2] * z + a[3], a[4] * x + a[5] * y + a[6] * z + a[7],
         a[8] * x + a[9] * y + a[10] * z + a[11]};
  }
}

// A subtree OpenSCAD must render: thrown by the 2D evaluation up to the
// enclosing 3D node.
struct NoNativeEquivalent {
  std::string what;
};

bool IsTwoD(const std::string& name) {
  return name == "circle" || name == "square" || name == "polygon" || name == "text" || name == "offset" ||
         name == "projection";
}

// Nodes that are 3D whatever their children (OpenSCAD ignores them under a
// 2D operation).
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

// multmatrix(m): the 4x4 argument as an affine map.
Affine MatrixOf(const CsgNode& n) {
  Affine a = kIdentity;
  auto it = n.args.find("m");  // OpenSCAD writes the matrix as the first positional argument
  const CsgValue* matrix = it != n.args.end() ? &it->second : n.positional.empty() ? nullptr : &n.positional[0];
  if (!matrix || matrix->items.size() < 3) throw NoNativeEquivalent{"multmatrix without a 4x4 matrix"};
  for (int r = 0; r < 3; ++r) {
    std::vector<double> row = Numbers(matrix->items[r]);
    if (row.size() < 4) throw NoNativeEquivalent{"multmatrix with a short row"};
    for (int k = 0; k < 4; ++k) a[4 * r + k] = row[k];
  }
  // A last row (0, 0, 0, w) scales by 1/w, as OpenSCAD applies the matrix
  // to homogeneous points; any other last row is a projection.
  if (matrix->items.size() >= 4) {
    const std::vector<double> w = Numbers(matrix->items[3]);
    if (w.size() >= 4 && (w[0] != 0 || w[1] != 0 || w[2] != 0 || w[3] == 0))
      throw NoNativeEquivalent{"multmatrix with a projective last row"};
    if (w.size() >= 4 && w[3] != 1)
      for (double& x : a) x /= w[3];
  }
  return a;
}

// A 2D shape as closed loops (after the 2D transform) combined by booleans.
struct Shape2 {
  enum class Op { kLoops, kUnion, kDifference, kIntersection } op = Op::kLoops;
  std::vector<Loop> loops;  // kLoops: filled by the even-odd rule
  std::vector<Shape2> parts;
};

bool PointInLoop(const scad::Point2& p, const Loop& loop) {
  bool inside = false;
  for (std::size_t i = 0, j = loop.size() - 1; i < loop.size(); j = i++) {
    const auto& a = loop[i];
    const auto& b = loop[j];
    if ((a[1] > p[1]) != (b[1] > p[1]) && p[0] < (b[0] - a[0]) * (p[1] - a[1]) / (b[1] - a[1]) + a[0]) inside = !inside;
  }
  return inside;
}

// Whether p lies in the shape: an odd number of a loop set's loops, then the booleans.
bool Inside(const Shape2& s, const scad::Point2& p) {
  if (s.op == Shape2::Op::kLoops) {
    bool in = false;
    for (const auto& l : s.loops) in ^= PointInLoop(p, l);
    return in;
  }
  if (s.parts.empty()) return false;
  bool in = Inside(s.parts[0], p);
  for (std::size_t i = 1; i < s.parts.size(); ++i) {
    const bool x = Inside(s.parts[i], p);
    if (s.op == Shape2::Op::kUnion)
      in = in || x;
    else if (s.op == Shape2::Op::kDifference)
      in = in && !x;
    else
      in = in && x;
  }
  return in;
}

void CollectLoops(const Shape2& s, std::vector<Loop>& out) {
  out.insert(out.end(), s.loops.begin(), s.loops.end());
  for (const auto& p : s.parts) CollectLoops(p, out);
}

void CollectPoints(const Shape2& s, std::vector<scad::Point2>& out) {
  for (const auto& l : s.loops) out.insert(out.end(), l.begin(), l.end());
  for (const auto& p : s.parts) CollectPoints(p, out);
}

// 2D transform: rows (a b tx; c d ty).
using Affine2 = std::array<double, 6>;

Loop Apply(const Affine2& t, const Loop& l) {
  Loop out;
  for (const auto& p : l) out.push_back({t[0] * p[0] + t[1] * p[1] + t[2], t[3] * p[0] + t[4] * p[1] + t[5]});
  return out;
}

// OpenSCAD's own outline of a 2D subtree with no native equivalent (text,
// offset, projection, 2D imports), in the subtree's coordinates.
using Render2 = std::function<std::vector<Loop>(const CsgNode&)>;

Shape2 Evaluate2(const CsgNode& n, const Affine2& t, const Render2& render2) {
  Shape2 s;
  const std::string& name = n.name;
  if (name == "circle") {
    const double r = n.Number("r", 1);
    if (r > 0) s.loops.push_back(Apply(t, scad::CircleLoop(r, FragmentsOf(n, r))));
    return s;
  }
  if (name == "square") {
    auto it = n.args.find("size");
    double x = 1, y = 1;
    if (it != n.args.end()) {
      if (it->second.type == CsgValue::Type::kVector) {
        auto v = Numbers(it->second);
        if (v.size() >= 2) x = v[0], y = v[1];
      } else {
        x = y = Num(it->second, 1);
      }
    }
    if (x > 0 && y > 0) s.loops.push_back(Apply(t, scad::SquareLoop(x, y, n.Boolean("center", false))));
    return s;
  }
  if (name == "polygon") {
    auto pts = n.args.find("points");
    if (pts == n.args.end()) return s;
    std::vector<scad::Point2> points;
    for (const auto& p : pts->second.items) {
      auto v = Numbers(p);
      if (v.size() < 2) throw NoNativeEquivalent{"polygon point without x and y"};
      points.push_back({v[0], v[1]});
    }
    auto paths = n.args.find("paths");
    if (paths == n.args.end() || paths->second.type != CsgValue::Type::kVector) {
      if (points.size() >= 3) s.loops.push_back(Apply(t, points));
    } else {
      for (const auto& path : paths->second.items) {
        Loop loop;
        for (double i : Numbers(path)) {
          if (i < 0 || i >= static_cast<double>(points.size()))
            throw NoNativeEquivalent{"polygon path index out of range"};
          loop.push_back(points[static_cast<std::size_t>(i)]);
        }
        if (loop.size() >= 3) s.loops.push_back(Apply(t, loop));
      }
    }
    return s;
  }
  if (name == "multmatrix") {
    const Affine m = MatrixOf(n);
    const Affine2 m2 = {m[0], m[1], m[3], m[4], m[5], m[7]};
    const Affine2 c = {t[0] * m2[0] + t[1] * m2[3], t[0] * m2[1] + t[1] * m2[4], t[0] * m2[2] + t[1] * m2[5] + t[2],
                       t[3] * m2[0] + t[4] * m2[3], t[3] * m2[1] + t[4] * m2[4], t[3] * m2[2] + t[4] * m2[5] + t[5]};
    s.op = Shape2::Op::kUnion;
    for (const auto& c2 : n.children) s.parts.push_back(Evaluate2(c2, c, render2));
    return s;
  }
  if (name == "group" || name == "union" || name == "render" || name == "color") {
    s.op = Shape2::Op::kUnion;
  } else if (name == "difference") {
    s.op = Shape2::Op::kDifference;
  } else if (name == "intersection") {
    s.op = Shape2::Op::kIntersection;
  } else if (name == "hull") {
    Shape2 all;
    all.op = Shape2::Op::kUnion;
    for (const auto& c : n.children) all.parts.push_back(Evaluate2(c, t, render2));
    std::vector<scad::Point2> points;
    CollectPoints(all, points);
    Loop h = ConvexHull2D(points);
    if (h.size() >= 3) s.loops.push_back(h);
    return s;
  } else if (IsThreeD(name)) {
    return s;  // a 3D object among 2D ones: no material, as OpenSCAD ignores it (with a warning)
  } else {
    for (const Loop& l : render2(n)) s.loops.push_back(Apply(t, l));
    return s;
  }
  for (const auto& c : n.children) s.parts.push_back(Evaluate2(c, t, render2));
  return s;
}

// The least and the greatest x over the shape's points and the axis x = 0
// (what rotate_extrude turns about): {min(0, x...), max(0, x...)}.
std::pair<double, double> XRangeWithAxis(const Shape2& s) {
  std::pair<double, double> r{0, 0};
  auto take = [&r](double lo, double hi) {
    r.first = std::min(r.first, lo);
    r.second = std::max(r.second, hi);
  };
  for (const auto& l : s.loops)
    for (const auto& p : l) take(p[0], p[0]);
  for (const auto& p : s.parts) {
    const auto [lo, hi] = XRangeWithAxis(p);
    take(lo, hi);
  }
  return r;
}

// The signed distance (a bound: exact per loop set, min/max across the
// booleans) to a 2D shape; +infinity for nothing.
using Distance2 = std::function<double(double, double)>;

Distance2 RegionOf(const Shape2& s) {
  constexpr double kNothing = std::numeric_limits<double>::infinity();
  if (s.op == Shape2::Op::kLoops) {
    auto region = std::make_shared<const scad::RegionDistance>(s.loops);
    if (region->empty()) return [](double, double) { return kNothing; };
    return [region](double x, double y) { return (*region)(x, y); };
  }
  std::vector<Distance2> parts;
  for (const auto& p : s.parts) parts.push_back(RegionOf(p));
  if (parts.empty()) return [](double, double) { return kNothing; };
  const Shape2::Op op = s.op;
  return [parts = std::move(parts), op](double x, double y) {
    double d = parts[0](x, y);
    for (std::size_t i = 1; i < parts.size(); ++i) {
      const double e = parts[i](x, y);
      if (op == Shape2::Op::kUnion)
        d = std::min(d, e);
      else if (op == Shape2::Op::kDifference)
        d = std::max(d, -e);
      else
        d = std::max(d, e);
    }
    return d;
  };
}

// Grows [lo, hi] by the shape's bounding box: of a difference its first
// operand's, of an intersection the overlap of its operands' (so trimming
// with a huge square, `difference() { shape; square(4200); }`, keeps the
// shape's box), of a union every operand's.
void Bounds2(const Shape2& s, scad::Point2& lo, scad::Point2& hi) {
  for (const auto& l : s.loops)
    for (const auto& p : l)
      for (int k = 0; k < 2; ++k) {
        lo[k] = std::min(lo[k], p[k]);
        hi[k] = std::max(hi[k], p[k]);
      }
  if (s.op == Shape2::Op::kLoops || s.parts.empty()) return;
  if (s.op == Shape2::Op::kUnion) {
    for (const auto& p : s.parts) Bounds2(p, lo, hi);
    return;
  }
  constexpr double kInf = std::numeric_limits<double>::infinity();
  scad::Point2 plo{kInf, kInf}, phi{-kInf, -kInf};
  Bounds2(s.parts[0], plo, phi);
  for (std::size_t i = 1; i < s.parts.size() && s.op == Shape2::Op::kIntersection; ++i) {
    scad::Point2 qlo{kInf, kInf}, qhi{-kInf, -kInf};
    Bounds2(s.parts[i], qlo, qhi);
    for (int k = 0; k < 2; ++k) {
      plo[k] = std::max(plo[k], qlo[k]);
      phi[k] = std::min(phi[k], qhi[k]);
    }
  }
  if (!(plo[0] <= phi[0] && plo[1] <= phi[1])) return;  // nothing
  for (int k = 0; k < 2; ++k) {
    lo[k] = std::min(lo[k], plo[k]);
    hi[k] = std::max(hi[k], phi[k]);
  }
}

// The scale s of an affine map whose linear part is s times a rotation or
// reflection (A^T A = s^2 I), else 0: signed distances map exactly through it.
double SimilarityScale(const Affine& a) {
  const double c[3][3] = {{a[0], a[1], a[2]}, {a[4], a[5], a[6]}, {a[8], a[9], a[10]}};
  double g[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) g[i][j] = c[0][i] * c[0][j] + c[1][i] * c[1][j] + c[2][i] * c[2][j];
  const double s2 = (g[0][0] + g[1][1] + g[2][2]) / 3;
  if (!(s2 > 0)) return 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (std::abs(g[i][j] - (i == j ? s2 : 0)) > 1e-9 * s2) return 0;
  return std::sqrt(s2);
}

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

  void Append(const Field& f) {
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

  // Boolean node i: its operands in order, each its box distance where that
  // is `band` or more, else its own value (a primitive's or a boolean's).
  double Evaluate(std::size_t i, double x, double y, double z) const {
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

  std::vector<Node> nodes_;
  double band_;
};

// The boolean `op` of fields (FieldProgram evaluates it); nullptr: no
// material.
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

class CsgEvaluation {
 public:
  // mesh_road: every subtree an exact mesh (mesh::ExactBoolean and friends),
  // else today's level sets (docs/openscad.md, "Two roads").
  CsgEvaluation(OpenScadNodeContext& context, const fs::path& model, const fs::path& work, bool mesh_road)
      : c_(context), model_(model), work_(work), mesh_road_(mesh_road), render2_([this](const CsgNode& n) {
          return Outline2(n);
        }) {}

  // A subtree's geometry: a level set, or (while every node below is a
  // convex primitive, a straight prism or a boolean of them) its signed
  // distance bound not sampled yet, so a whole CSG tree of such nodes is
  // sampled once in its result's band instead of once per leaf plus a grid
  // copy per boolean. Both empty: no material.
  struct Result {
    Solid solid{};
    std::shared_ptr<const Field> field{};
    std::string key{};
    std::shared_ptr<const SubtreeTrace> trace{};  // with a subtree cache (null when found without one)
  };

  // need_solid: sample a field result (the root of the evaluation). Fields
  // are combined only without a subtree cache.
  Result Evaluate3(const CsgNode& n, const Affine& m, const std::string& path, bool need_solid = false) {
    const std::string key = KeyOf(n, m);
    SubtreeRecord record;
    record.key = key;
    record.topology = Sha256Hex("csg|" + Topology(n));
    record.path = path;
    record.op = kCsgNativeOp + n.name;
    if (c_.cache) {
      if (auto hit = c_.cache->Find(key)) {
        record.from_cache = true;
        record.bytes = hit->solid.MemoryBytes();
        // The records of its descendants and its outside meshes as its
        // trace holds them, else (a cache filled elsewhere) only the keys
        // of the children it was computed from.
        const SubtreeTrace* trace = hit->trace.get();
        if (trace && !trace->op.empty()) {
          if (c_.records) AppendDescendantRecords(*trace, path, c_.records);
          record.children = trace->children;
        } else {
          Affine inner;
          if (ChildFrame(n, m, &inner))
            for (const auto& c : n.children)
              if (!IsTwoD(c.name)) record.children.push_back(KeyOf(c, inner));
        }
        if (trace && c_.outside) c_.outside->insert(c_.outside->end(), trace->outside.begin(), trace->outside.end());
        if (c_.records) c_.records->push_back(record);
        return {hit->solid, nullptr, key, hit->trace};
      }
    }
    Result result{Solid(), nullptr, key};
    const std::size_t outside_before = c_.outside ? c_.outside->size() : 0;
    // Children first (3D nodes whose children are 3D), each its own record.
    std::vector<Result> kids;
    std::vector<std::string> kid_paths;  // below path
    Affine inner;
    const bool boolean = ChildFrame(n, m, &inner) || (mesh_road_ && MeshChildFrame(n, m, &inner));
    // OpenSCAD 2021.01 takes a 2D object among 3D ones as no material (with
    // a warning): it empties an intersection, and a difference it comes first in.
    bool two_d_child = false, two_d_first = false;
    if (boolean) {
      for (std::size_t i = 0; i < n.children.size(); ++i) {
        if (mesh_road_ ? scad::Dimension(n.children[i]) == 2 : IsTwoD(n.children[i].name)) {
          if (mesh_road_) {
            Warn(n.children[i].name + " (CSG line " + std::to_string(n.children[i].line) +
                 "): a 2D object among 3D ones is ignored, as OpenSCAD ignores it");
            two_d_first = two_d_first || kids.empty();
            two_d_child = true;
          }
          continue;
        }
        kid_paths.push_back("/" + std::to_string(i));
        kids.push_back(Evaluate3(n.children[i], inner, path + kid_paths.back()));
      }
    }
    const Stopwatch start;
    if (mesh_road_) {
      try {
        if (boolean && ((n.name == "intersection" && two_d_child) || (n.name == "difference" && two_d_first)))
          result.solid = Solid();
        else if (boolean)
          result.solid = MeshOfChildren(n, m, kids, record);
        else {
          leaf_path_ = path;
          result.solid = MeshLeaf(n, m);
        }
      } catch (const NoNativeEquivalent& e) {
        record.op = kCsgRenderedOp + n.name;
        result.solid = Rendered(n, m, e.what);
      }
    } else if (boolean) {
      const Combine op = n.name == "difference"     ? Combine::kDifference
                         : n.name == "intersection" ? Combine::kIntersection
                                                    : Combine::kUnion;
      bool all_fields = true;
      for (const auto& k : kids) all_fields = all_fields && (k.field || k.solid.empty());
      if (all_fields) {
        std::vector<std::shared_ptr<const Field>> fields;
        for (const auto& k : kids) fields.push_back(k.field);
        result.field = CombineFields(op, fields);
      } else {
        std::vector<Solid> solids;
        for (const auto& k : kids) solids.push_back(k.field ? Sample(*k.field) : k.solid);
        if (op == Combine::kUnion) {
          for (const auto& k : solids) result.solid = geometry::Union(result.solid, k);
        } else if (!solids.empty()) {
          result.solid = solids[0];
          for (std::size_t i = 1; i < solids.size(); ++i)
            result.solid = op == Combine::kDifference ? geometry::Difference(result.solid, solids[i])
                                                      : geometry::Intersection(result.solid, solids[i]);
        }
      }
    } else {
      try {
        result = Leaf(n, m);
        result.key = key;
      } catch (const NoNativeEquivalent& e) {
        record.op = kCsgRenderedOp + n.name;
        result.solid = Rendered(n, m, e.what);
      }
    }
    // With a subtree cache every node becomes a level set, so that each one
    // can be offered and found again in later samples (Fab Forms Sec. 6).
    if (result.field && (need_solid || c_.cache)) {
      result.solid = Sample(*result.field);
      result.field = nullptr;
    }
    record.seconds = start.Seconds();
    record.bytes = result.solid.MemoryBytes();
    for (const auto& k : kids) record.children.push_back(k.key);
    if (c_.cache && !result.field) {
      auto trace = std::make_shared<SubtreeTrace>();
      trace->topology = record.topology;
      trace->op = record.op;
      trace->bytes = record.bytes;
      trace->children = record.children;
      trace->child_paths = kid_paths;
      for (const auto& k : kids) trace->child_traces.push_back(k.trace);
      if (c_.outside) trace->outside.assign(c_.outside->begin() + outside_before, c_.outside->end());
      result.trace = trace;
      c_.cache->Offer(key, EntryOf(result.solid, std::move(trace)), record.seconds);
    }
    if (c_.records) c_.records->push_back(std::move(record));
    return result;
  }

 private:
  // The cache key of subtree n under the composed transform m.
  std::string KeyOf(const CsgNode& n, const Affine& m) const {
    return Sha256Hex(std::string(mesh_road_ ? "csg-mesh" : "csg") + "|voxel=" +
                     scad::FormatScadNumber(c_.grid.voxel_size) + "|m=" + AffineText(m) + "|" + n.canonical);
  }

  // Whether n is evaluated from its 3D children (booleans and multmatrix
  // with a native matrix), and the transform they are evaluated under.
  static bool ChildFrame(const CsgNode& n, const Affine& m, Affine* inner) {
    *inner = m;
    const bool boolean = n.name == "group" || n.name == "union" || n.name == "render" || n.name == "color" ||
                         n.name == "difference" || n.name == "intersection" || n.name == "multmatrix";
    if (n.name != "multmatrix") return boolean;
    try {
      *inner = Compose(m, MatrixOf(n));
    } catch (const NoNativeEquivalent&) {
      return false;  // rendered by OpenSCAD
    }
    return true;
  }

  static std::string Topology(const CsgNode& n) {
    std::string t = n.name + "(";
    for (const auto& c : n.children) t += Topology(c) + ";";
    return t + ")";
  }

  Solid FromMesh(mesh::TriangleMesh m, const Affine& a) {
    if (m.triangles.empty()) return Solid();
    Transform(m, a);
    return geometry::FromMesh(c_.grid, m);
  }

  // A closed convex mesh (OpenSCAD's cubes, spheres, cylinders, hulls) under
  // a: its exact distance as a field; a level set when it is not convex.
  Result Convex(mesh::TriangleMesh m, const Affine& a) {
    if (m.triangles.empty()) return {};
    Transform(m, a);
    geometry::DistanceFunction d = geometry::ConvexMeshDistance(m, c_.grid.half_width_voxels * c_.grid.voxel_size);
    if (!d) return {geometry::FromMesh(c_.grid, m), nullptr, ""};
    auto field = std::make_shared<Field>();
    field->leaf = std::move(d);
    field->bounds = {m.vertices[0], m.vertices[0]};
    for (const auto& v : m.vertices)
      for (int k = 0; k < 3; ++k) {
        field->bounds.min[k] = std::min(field->bounds.min[k], v[k]);
        field->bounds.max[k] = std::max(field->bounds.max[k], v[k]);
      }
    return {Solid(), field, ""};
  }

  // A field sampled in its band (geometry::FromDistance).
  Solid Sample(const Field& f) {
    try {
      if (f.parts.empty()) return geometry::FromDistance(c_.grid, f.bounds, f.leaf, "csg");
      const FieldProgram program(f, c_.grid.half_width_voxels * c_.grid.voxel_size);
      return geometry::FromDistance(
          c_.grid, f.bounds, [&program](double x, double y, double z) { return program(x, y, z); }, "csg");
    } catch (const InputError& e) {
      throw SampleFailure(kNoGeometry, model_.filename().string() + ": " + e.what());
    }
  }

  void Outside(const std::string& what, const std::string& key, const mesh::TriangleMesh& m) {
    if (c_.outside) c_.outside->push_back({what, key, std::make_shared<const mesh::TriangleMesh>(m)});
  }

  Solid Extruded(const Shape2& s, const std::function<mesh::TriangleMesh(const Loop&)>& build, const Affine& m) {
    if (s.op == Shape2::Op::kLoops) {
      // Even-odd: a loop inside an odd number of others is a hole.
      Solid filled, holes;
      for (std::size_t i = 0; i < s.loops.size(); ++i) {
        int depth = 0;
        for (std::size_t j = 0; j < s.loops.size(); ++j)
          if (i != j && PointInLoop(s.loops[i][0], s.loops[j])) ++depth;
        Solid one = FromMesh(build(s.loops[i]), m);
        if (depth % 2)
          holes = geometry::Union(holes, one);
        else
          filled = geometry::Union(filled, one);
      }
      return holes.empty() || filled.empty() ? filled : geometry::Difference(filled, holes);
    }
    Solid acc;
    bool first = true;
    for (const auto& p : s.parts) {
      Solid x = Extruded(p, build, m);
      if (first)
        acc = x;
      else if (s.op == Shape2::Op::kUnion)
        acc = geometry::Union(acc, x);
      else if (s.op == Shape2::Op::kDifference)
        acc = geometry::Difference(acc, x);
      else
        acc = geometry::Intersection(acc, x);
      first = false;
    }
    return acc;
  }

  // Points of a subtree made only of primitives, groups and transforms (for hull).
  void HullPoints(const CsgNode& n, const Affine& m, std::vector<std::array<double, 3>>& out) {
    if (n.name == "multmatrix" || n.name == "group" || n.name == "union" || n.name == "hull" || n.name == "render" ||
        n.name == "color") {
      const Affine inner = n.name == "multmatrix" ? Compose(m, MatrixOf(n)) : m;
      for (const auto& c : n.children) HullPoints(c, inner, out);
      return;
    }
    mesh::TriangleMesh mm = PrimitiveMesh(n);
    Transform(mm, m);
    out.insert(out.end(), mm.vertices.begin(), mm.vertices.end());
  }

  mesh::TriangleMesh PrimitiveMesh(const CsgNode& n) {
    if (n.name == "cube") {
      std::array<double, 3> size{1, 1, 1};
      auto it = n.args.find("size");
      if (it != n.args.end()) {
        if (it->second.type == CsgValue::Type::kVector) {
          auto v = Numbers(it->second);
          if (v.size() >= 3) size = {v[0], v[1], v[2]};
        } else {
          size = {Num(it->second, 1), Num(it->second, 1), Num(it->second, 1)};
        }
      }
      if (size[0] <= 0 || size[1] <= 0 || size[2] <= 0) return {};
      return scad::CubeMesh(size, n.Boolean("center", false));
    }
    if (n.name == "sphere") {
      const double r = n.Number("r", 1);
      if (r <= 0) return {};
      return scad::SphereMesh(r, FragmentsOf(n, r));
    }
    if (n.name == "cylinder") {
      const double h = n.Number("h", 1), r1 = n.Number("r1", 1), r2 = n.Number("r2", 1);
      if (h <= 0 || r1 < 0 || r2 < 0 || (r1 == 0 && r2 == 0)) return {};
      return scad::CylinderMesh(h, r1, r2, n.Boolean("center", false), FragmentsOf(n, std::max(r1, r2)));
    }
    if (n.name == "polyhedron") {
      std::vector<std::array<double, 3>> points;
      auto p = n.args.find("points");
      if (p == n.args.end()) return {};
      for (const auto& v : p->second.items) {
        auto x = Numbers(v);
        if (x.size() < 3) throw NoNativeEquivalent{"polyhedron point without x, y, z"};
        points.push_back({x[0], x[1], x[2]});
      }
      auto f = n.args.find("faces");
      if (f == n.args.end()) f = n.args.find("triangles");
      if (f == n.args.end()) return {};
      std::vector<std::vector<int>> faces;
      for (const auto& face : f->second.items) {
        std::vector<int> ids;
        for (double i : Numbers(face)) {
          if (i < 0 || i >= static_cast<double>(points.size()))
            throw NoNativeEquivalent{"polyhedron face index out of range"};
          ids.push_back(static_cast<int>(i));
        }
        faces.push_back(ids);
      }
      return scad::PolyhedronMesh(points, faces);
    }
    throw NoNativeEquivalent{n.name};
  }

  Result Leaf(const CsgNode& n, const Affine& m) {
    if (n.name == "cube" || n.name == "sphere" || n.name == "cylinder") return Convex(PrimitiveMesh(n), m);
    if (n.name == "polyhedron") {
      mesh::TriangleMesh mm = PrimitiveMesh(n);
      Outside(model_.filename().string() + ": polyhedron (CSG line " + std::to_string(n.line) + ")",
              Sha256Hex(n.canonical), mm);
      return {FromMesh(std::move(mm), m), nullptr, ""};
    }
    if (n.name == "linear_extrude") {
      Shape2 s;
      s.op = Shape2::Op::kUnion;
      for (const auto& c : n.children) s.parts.push_back(Evaluate2(c, {1, 0, 0, 0, 1, 0}, render2_));
      const double h = n.Number("height", 100), twist = n.Number("twist", 0);
      if (h <= 0) return {};
      scad::Point2 scale{1, 1};
      if (auto it = n.args.find("scale"); it != n.args.end()) {
        if (it->second.type == CsgValue::Type::kVector) {
          auto v = Numbers(it->second);
          if (v.size() >= 2) scale = {v[0], v[1]};
        } else {
          scale = {Num(it->second, 1), Num(it->second, 1)};
        }
      }
      const bool center = n.Boolean("center", false);
      if (twist == 0 && scale[0] == 1 && scale[1] == 1)
        if (std::optional<Result> prism = Prism(s, h, center, m)) return *prism;
      // Twisted or scaled: the walls are built from the outline of the whole
      // 2D child, as OpenSCAD builds them (a twisted wall's triangles are not
      // those of its loops' own extrusions, so their 3D booleans differ).
      std::vector<Loop> loops;
      CollectLoops(s, loops);
      const scad::Region2 region = scad::ResolveRegion(loops, [&](const scad::Point2& p) { return Inside(s, p); });
      if (region.triangles.empty()) return {};
      double r_sqr = 0, delta_sqr = 0;
      for (const auto& loop : region.loops)
        for (int i : loop) {
          const scad::Point2& p = region.points[i];
          r_sqr = std::max(r_sqr, p[0] * p[0] + p[1] * p[1]);
          const double dx = p[0] * (1 - scale[0]), dy = p[1] * (1 - scale[1]);
          delta_sqr = std::max(delta_sqr, dx * dx + dy * dy);
        }
      int slices = static_cast<int>(n.Number("slices", 0));
      if (slices <= 0)
        slices = scad::ExtrudeSlices(r_sqr, delta_sqr, h, twist, scale, n.Number("$fn", 0), n.Number("$fs", 2),
                                     n.Number("$fa", 12));
      return {FromMesh(scad::LinearExtrudeMesh(region, h, center, twist, slices, scale), m), nullptr, ""};
    }
    if (n.name == "rotate_extrude") {
      Shape2 s;
      s.op = Shape2::Op::kUnion;
      for (const auto& c : n.children) s.parts.push_back(Evaluate2(c, {1, 0, 0, 0, 1, 0}, render2_));
      const auto [min_x, max_x] = XRangeWithAxis(s);
      if (min_x < 0) throw NoNativeEquivalent{"rotate_extrude of points with x < 0"};
      const double angle = std::clamp(n.Number("angle", 360), -360.0, 360.0);
      // OpenSCAD 2021.01 truncates: 31 fragments through 180 degrees are 15 sectors.
      const int fragments = static_cast<int>(std::max(FragmentsOf(n, max_x) * std::abs(angle) / 360, 1.0));
      return {Extruded(
                  s, [&](const Loop& l) { return scad::RotateExtrudeMesh(l, angle, fragments); }, m),
              nullptr, ""};
    }
    if (n.name == "hull") {
      std::vector<std::array<double, 3>> points;
      for (const auto& c : n.children) HullPoints(c, kIdentity, points);
      if (points.size() < 4) return {};
      return Convex(mesh::ConvexHull(points), m);
    }
    if (n.name == "import") {
      auto f = n.args.find("file");
      if (f == n.args.end() || f->second.type != CsgValue::Type::kString) throw NoNativeEquivalent{"import"};
      fs::path file = f->second.text;
      std::string ext = file.extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
      if (ext != ".stl" && ext != ".off" && ext != ".obj" && ext != ".3mf" && ext != ".amf")
        throw NoNativeEquivalent{"import of " + ext};
      if (file.is_relative()) file = model_.parent_path() / file;
      mesh::TriangleMesh mm;
      try {
        mm = mesh::ReadMesh(file);
      } catch (const InputError& e) {
        throw SampleFailure(kNoGeometry, e.what());
      }
      Outside(file.string() + " (imported by " + model_.filename().string() + ")", Sha256Hex(n.canonical), mm);
      return {FromMesh(std::move(mm), m), nullptr, ""};
    }
    throw NoNativeEquivalent{n.name};
  }

  // OpenSCAD exports this subtree alone (its canonical text is a program,
  // written as work_/<stem>-<k>.scad) to that path + `extension`, returned in
  // `out`; false with `run` telling why when it cannot.
  bool ExportSubtree(const CsgNode& n, const std::string& stem, const std::string& extension, fs::path& out,
                     scad::OpenScadRun& run) {
    LinkModelFiles();
    const fs::path program = work_ / (stem + "-" + std::to_string(++rendered_) + ".scad");
    out = program.string() + extension;
    {
      std::ofstream text(program);
      text << n.canonical << "\n";
    }
    return scad::RunOpenScad(program, out, {}, &run);
  }

  // OpenSCAD renders this subtree alone.
  Solid Rendered(const CsgNode& n, const Affine& m, const std::string& why) {
    fs::path stl;
    scad::OpenScadRun run;
    const bool rendered = ExportSubtree(n, "subtree", ".stl", stl, run);
    if (!rendered && mesh_road_) {
      // OpenSCAD renders the whole model, so a subtree it cannot render on
      // its own is one it leaves empty there ("Current top level object is
      // empty"): no material, named in the log.
      Warn(n.name + " (CSG line " + std::to_string(n.line) + "): OpenSCAD renders it to no material (" + run.log_tail +
           ")");
      return Solid();
    }
    if (!rendered)
      throw SampleFailure(kNoGeometry, model_.string() + ": OpenSCAD could not render " + n.name + " (CSG line " +
                                           std::to_string(n.line) + ", no native " + why + "): " + run.log_tail);
    mesh::TriangleMesh mm;
    try {
      mm = mesh::ReadMesh(stl);
    } catch (const InputError& e) {
      if (mesh_road_) {  // OpenSCAD renders this subtree to nothing: no material, as in OpenSCAD's own render
        Warn(n.name + " (CSG line " + std::to_string(n.line) + "): OpenSCAD renders it to no material (" + e.what() +
             ")");
        return Solid();
      }
      throw SampleFailure(kNoGeometry, model_.string() + ": OpenSCAD's render of " + n.name + ": " + e.what());
    }
    Outside(
        model_.filename().string() + ": OpenSCAD's render of " + n.name + " (CSG line " + std::to_string(n.line) + ")",
        Sha256Hex(n.canonical), mm);
    if (mesh_road_) return MeshOf(std::move(mm), m);
    return FromMesh(std::move(mm), m);
  }

  // OpenSCAD's 2D SVG export of a 2D subtree (its canonical text is a
  // program): a 2D export is cheap next to a 3D render, and the outline is
  // then extruded natively. Outlines are remembered per canonical text for
  // the process (a text's glyphs are the same in every sample with that
  // text), up to kOutlineBytes in all; beyond that all are forgotten at once
  // and remembering starts again. Throws NoNativeEquivalent when OpenSCAD
  // cannot export it.
  static constexpr std::size_t kOutlineBytes = std::size_t{32} << 20;
  std::vector<Loop> Outline2(const CsgNode& n) {
    static std::mutex mutex;
    static std::map<std::string, std::vector<Loop>> outlines;
    static std::size_t outline_bytes = 0;
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (auto it = outlines.find(n.canonical); it != outlines.end()) return it->second;
    }
    fs::path svg;
    scad::OpenScadRun run;
    if (!ExportSubtree(n, "outline", ".svg", svg, run))
      throw NoNativeEquivalent{n.name + " (no 2D outline: " + run.log_tail + ")"};
    std::string text;
    {
      std::ifstream in(svg, std::ios::binary);
      std::stringstream ss;
      ss << in.rdbuf();
      text = ss.str();
    }
    std::vector<Loop> loops;
    try {
      loops = scad::ReadSvgOutline(text, model_.filename().string() + ": OpenSCAD's outline of " + n.name);
    } catch (const InputError& e) {
      throw NoNativeEquivalent{e.what()};
    }
    std::size_t bytes = n.canonical.size() + sizeof(std::vector<Loop>);
    for (const Loop& l : loops) bytes += sizeof(Loop) + l.size() * sizeof(scad::Point2);
    std::lock_guard<std::mutex> lock(mutex);
    if (outline_bytes + bytes > kOutlineBytes) {
      outlines.clear();
      outline_bytes = 0;
    }
    if (outlines.emplace(n.canonical, loops).second) outline_bytes += bytes;
    return loops;
  }

  // A straight linear_extrude (no twist, no scale) under a similarity: the
  // prism's signed distance from the outline's (exact per loop set), as a
  // field. Empty when the map is not a similarity (then meshes).
  std::optional<Result> Prism(const Shape2& s, double h, bool center, const Affine& m) {
    const double scale = SimilarityScale(m);
    if (scale <= 0) return std::nullopt;
    scad::Point2 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
    scad::Point2 hi{-lo[0], -lo[1]};
    Bounds2(s, lo, hi);
    if (!(lo[0] <= hi[0] && lo[1] <= hi[1])) return Result{};
    const double z0 = center ? -h / 2 : 0, zc = z0 + h / 2;
    Distance2 region = RegionOf(s);
    geometry::Box3 box{{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                        std::numeric_limits<double>::infinity()},
                       {-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                        -std::numeric_limits<double>::infinity()}};
    for (int k = 0; k < 8; ++k) {
      const double x = k & 1 ? hi[0] : lo[0], y = k & 2 ? hi[1] : lo[1], z = k & 4 ? z0 + h : z0;
      const double w[3] = {m[0] * x + m[1] * y + m[2] * z + m[3], m[4] * x + m[5] * y + m[6] * z + m[7],
                           m[8] * x + m[9] * y + m[10] * z + m[11]};
      for (int a = 0; a < 3; ++a) {
        box.min[a] = std::min(box.min[a], w[a]);
        box.max[a] = std::max(box.max[a], w[a]);
      }
    }
    const double inv = 1 / (scale * scale);
    const double band = c_.grid.half_width_voxels * c_.grid.voxel_size / scale;  // local mm
    auto shared = std::make_shared<const Distance2>(std::move(region));
    // An id per outline, never reused (a freed outline's address may be).
    static std::atomic<std::uint64_t> next_id{0};
    const std::uint64_t id = ++next_id;
    auto distance = [m, inv, scale, zc, h, band, shared, id](double x, double y, double z) {
      const double px = x - m[3], py = y - m[7], pz = z - m[11];  // local = A^T (p - t) / s^2
      const double qx = (m[0] * px + m[4] * py + m[8] * pz) * inv;
      const double qy = (m[1] * px + m[5] * py + m[9] * pz) * inv;
      const double qz = (m[2] * px + m[6] * py + m[10] * pz) * inv;
      const double b = std::abs(qz - zc) - h / 2;
      if (b >= band) return scale * b;  // beyond the band above or below: a lower bound
      // The sampler visits a leaf's voxels z fastest: for a prism standing
      // along z the outline's distance repeats, so the last one is kept.
      thread_local std::uint64_t last_region = 0;
      thread_local double last_x = 0, last_y = 0, last_a = 0;
      if (last_region != id || last_x != qx || last_y != qy) {
        last_region = id;
        last_x = qx;
        last_y = qy;
        last_a = (*shared)(qx, qy);
      }
      const double a = last_a;
      const double oa = std::max(a, 0.0), ob = std::max(b, 0.0);
      return scale * (std::sqrt(oa * oa + ob * ob) + std::min(std::max(a, b), 0.0));
    };
    auto field = std::make_shared<Field>();
    field->leaf = distance;
    field->bounds = box;
    return Result{Solid(), field, ""};
  }

  // A subtree's program runs in the work directory, where the files the
  // model imports by relative name (`import("x.dxf")`) must be found too:
  // they are linked there once (model_files.h).
  void LinkModelFiles() {
    if (linked_) return;
    linked_ = true;
    std::error_code ec;
    // A model evaluated where it lies may name files outside its directory
    // (OpenSCAD reads them; a job bundle refuses such a model at submit and
    // a worker before it reads anything, model_files.h): those are not linked.
    std::vector<scad::ModelFile> files;
    try {
      files = scad::ModelFiles(model_);
    } catch (const InputError&) {
    }
    for (const scad::ModelFile& f : files) {
      fs::create_directories((work_ / f.relative).parent_path(), ec);
      fs::create_symlink(fs::absolute(f.source), work_ / f.relative, ec);
    }
  }

  // ---- The mesh road ---------------------------------------------------------

  // Nodes evaluated from their 3D children on the mesh road beyond the
  // booleans and multmatrix: hull (children in the world frame: a hull
  // commutes with affine maps), minkowski and resize (children in their own
  // frame, the result mapped by m: a Minkowski sum would count m's
  // translation once per operand, a resize reads the child's own box).
  static bool MeshChildFrame(const CsgNode& n, const Affine& m, Affine* inner) {
    if (n.name == "hull") {
      *inner = m;
      return std::any_of(n.children.begin(), n.children.end(),
                         [](const CsgNode& c) { return scad::Dimension(c) == 3; });
    }
    if (n.name == "minkowski" || n.name == "resize") {
      *inner = kIdentity;
      return true;
    }
    return false;
  }

  // An exact mesh under a as a mesh solid; a mesh with a reflection is
  // turned inside out by the map, so its triangles are reversed.
  Solid MeshOf(mesh::TriangleMesh mm, const Affine& a) {
    Transform(mm, a);
    const double det =
        a[0] * (a[5] * a[10] - a[6] * a[9]) - a[1] * (a[4] * a[10] - a[6] * a[8]) + a[2] * (a[4] * a[9] - a[5] * a[8]);
    if (det < 0)
      for (auto& t : mm.triangles) std::swap(t[1], t[2]);
    try {
      return geometry::MeshSolid(c_.grid, std::move(mm));
    } catch (const InputError& e) {
      Warn("CSG: " + std::string(e.what()) + "; the object is left out, as OpenSCAD leaves it out");
      return Solid();
    }
  }

 public:
  // a minus every solid of `others` (the parts' disjointness: an earlier
  // part keeps what it shares with a later one), as a difference node would.
  Solid Minus(const Solid& a, const std::vector<Solid>& others) {
    if (a.empty() || others.empty()) return a;
    if (!mesh_road_) {
      Solid out = a;
      for (const Solid& b : others) out = geometry::Difference(out, b);
      return out;
    }
    CsgNode n;
    n.name = "difference";
    std::vector<Result> kids{{a, nullptr, ""}};
    for (const Solid& b : others) kids.push_back({b, nullptr, ""});
    SubtreeRecord record;
    return MeshOfChildren(n, kIdentity, kids, record);
  }

 private:
  void Warn(const std::string& text) {
    if (c_.warnings) c_.warnings->push_back(model_.filename().string() + ": " + text);
  }

  // A boolean, hull, minkowski or resize of evaluated children (kids: the
  // 3D children in order) on the mesh road. Operands that are not meshes (a
  // level-set fallback below) or that the exact booleans cannot take make it
  // a level-set boolean, named in the record ("csg-levelset:") and the log.
  Solid MeshOfChildren(const CsgNode& n, const Affine& m, const std::vector<Result>& kids, SubtreeRecord& record) {
    const std::string where = n.name + " (CSG line " + std::to_string(n.line) + ")";
    if (n.name == "hull") {
      std::vector<std::array<double, 3>> points;
      for (const auto& k : kids) {
        if (k.solid.empty()) continue;
        const mesh::TriangleMesh mm = k.solid.ToMesh();
        points.insert(points.end(), mm.vertices.begin(), mm.vertices.end());
      }
      return MeshOf(mesh::ConvexHull(points), kIdentity);
    }
    std::vector<mesh::TriangleMesh> operands;
    bool meshes = true;
    for (const auto& k : kids) {
      if (k.solid.empty())
        operands.emplace_back();
      else if (const mesh::TriangleMesh* b = k.solid.boundary())
        operands.push_back(*b);
      else
        meshes = false;
    }
    if (n.name == "resize") return MeshResized(n, m, kids);
    if (n.name == "minkowski") {
      if (!meshes) throw NoNativeEquivalent{"minkowski of a level set"};
      mesh::BooleanSummary summary;
      try {
        return MeshOf(mesh::MinkowskiSum(operands, &summary), m);
      } catch (const InputError& e) {
        throw NoNativeEquivalent{"minkowski: " + std::string(e.what())};
      }
    }
    const mesh::BooleanOp op = n.name == "difference"     ? mesh::BooleanOp::kDifference
                               : n.name == "intersection" ? mesh::BooleanOp::kIntersection
                                                          : mesh::BooleanOp::kUnion;
    // One child (a transform, a colour, a group of one): the child itself.
    if (op == mesh::BooleanOp::kUnion && kids.size() == 1) return kids[0].solid;
    if (kids.empty()) return Solid();
    if (meshes) {
      mesh::BooleanSummary summary;
      try {
        Solid out = MeshOf(mesh::ExactBoolean(op, operands, &summary), kIdentity);
        if (summary.nef) Warn(where + ": computed with Nef polyhedra (" + summary.nef_why + ")");
        return out;
      } catch (const InputError& e) {
        Warn(where + ": " + e.what() + "; evaluated with level sets instead");
      }
    } else {
      Warn(where + ": an operand is a level set; evaluated with level sets");
    }
    record.op = std::string(kCsgLevelSetOp) + n.name;
    Solid acc;
    bool first = true;
    for (const auto& k : kids) {
      if (first)
        acc = k.solid;
      else if (op == mesh::BooleanOp::kUnion)
        acc = geometry::Union(acc, k.solid);
      else if (op == mesh::BooleanOp::kDifference)
        acc = geometry::Difference(acc, k.solid);
      else
        acc = geometry::Intersection(acc, k.solid);
      first = false;
    }
    return acc;
  }

  // resize(newsize, auto): the child's own box scaled per axis to newsize;
  // an axis of newsize 0 keeps its size, or with auto takes the largest
  // scale of the axes given (OpenSCAD User Manual, "resize").
  Solid MeshResized(const CsgNode& n, const Affine& m, const std::vector<Result>& kids) {
    if (kids.empty() || kids[0].solid.empty()) return Solid();
    const Solid& child = kids[0].solid;
    const geometry::Box3 box = child.BoundingBox();
    std::vector<double> size = {0, 0, 0};
    std::vector<bool> automatic = {false, false, false};
    if (auto it = n.args.find("newsize"); it != n.args.end()) {
      const auto v = Numbers(it->second);
      for (std::size_t i = 0; i < 3 && i < v.size(); ++i) size[i] = v[i];
    }
    if (auto it = n.args.find("auto"); it != n.args.end()) {
      if (it->second.type == CsgValue::Type::kBoolean)
        automatic = {it->second.boolean, it->second.boolean, it->second.boolean};
      for (std::size_t i = 0; i < 3 && i < it->second.items.size(); ++i)
        automatic[i] = it->second.items[i].type == CsgValue::Type::kBoolean ? it->second.items[i].boolean
                                                                            : Num(it->second.items[i], 0) != 0;
    }
    double scale[3] = {1, 1, 1}, largest = 0;
    for (int i = 0; i < 3; ++i) {
      const double extent = box.max[i] - box.min[i];
      if (size[i] > 0 && extent > 0) {
        scale[i] = size[i] / extent;
        largest = std::max(largest, scale[i]);
      }
    }
    for (int i = 0; i < 3; ++i)
      if (size[i] <= 0 && automatic[i] && largest > 0) scale[i] = largest;
    const Affine s = {scale[0], 0, 0, 0, 0, scale[1], 0, 0, 0, 0, scale[2], 0};
    return MeshOf(child.ToMesh(), Compose(m, s));
  }

  // A mesh turned outward when it encloses a negative volume (an inverted
  // polyhedron, as OpenSCAD flips it).
  static mesh::TriangleMesh Outward(mesh::TriangleMesh mm) {
    if (mesh::EnclosedVolume(mm) < 0)
      for (auto& t : mm.triangles) std::swap(t[1], t[2]);
    return mm;
  }

  // A leaf on the mesh road: OpenSCAD's own polygon mesh of it.
  Solid MeshLeaf(const CsgNode& n, const Affine& m) {
    if (n.name == "cube" || n.name == "sphere" || n.name == "cylinder") return MeshOf(PrimitiveMesh(n), m);
    if (n.name == "polyhedron") {
      mesh::TriangleMesh mm = PrimitiveMesh(n);
      for (const auto& v : mm.vertices)
        if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) {
          Warn("polyhedron (CSG line " + std::to_string(n.line) +
               "): a point is not finite; left out, as OpenSCAD's render of it encloses nothing");
          return Solid();
        }
      Outside(model_.filename().string() + ": polyhedron (CSG line " + std::to_string(n.line) + ")",
              Sha256Hex(n.canonical), mm);
      mm = Outward(std::move(mm));
      // OpenSCAD renders an approximately convex polyhedron as its hull.
      if (scad::ApproximatelyConvex(mm)) mm = mesh::ConvexHull(mm.vertices);
      return MeshOf(std::move(mm), m);
    }
    if (n.name == "linear_extrude" || n.name == "rotate_extrude") {
      // The 2D child as OpenSCAD computes it (Clipper), extruded to
      // OpenSCAD's mesh (evaluate_2d.h); projections below evaluate their
      // 3D children on this road, texts and 2D imports are OpenSCAD's outlines.
      scad::Evaluate2dOptions options;
      options.model_dir = model_.parent_path();
      options.outline = [this](const CsgNode& c) { return Outline2(c); };
      options.mesh3d = [this](const CsgNode& c) {
        return Evaluate3(c, kIdentity, leaf_path_ + "/" + std::to_string(++projections_)).solid.ToMesh();
      };
      std::vector<std::string> warnings;
      mesh::TriangleMesh mm;
      try {
        mm = n.name == "linear_extrude" ? scad::LinearExtrude(n, options, &warnings)
                                        : scad::RotateExtrude(n, options, &warnings);
      } catch (const scad::NoNativeEquivalentError& e) {
        throw NoNativeEquivalent{e.what()};
      } catch (const InputError& e) {  // an import outside the model's directory
        throw SampleFailure(kNoGeometry, model_.filename().string() + ": " + e.what());
      }
      for (const std::string& w : warnings) Warn(n.name + " (CSG line " + std::to_string(n.line) + "): " + w);
      return MeshOf(std::move(mm), m);
    }
    if (n.name == "import") {
      auto f = n.args.find("file");
      if (f == n.args.end() || f->second.type != CsgValue::Type::kString) throw NoNativeEquivalent{"import"};
      fs::path file = f->second.text;
      std::string ext = file.extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
      if (ext == ".dxf" || ext == ".svg") return Solid();  // 2D: OpenSCAD ignores it among 3D objects
      if (ext != ".stl" && ext != ".off" && ext != ".obj" && ext != ".3mf" && ext != ".amf")
        throw NoNativeEquivalent{"import of " + ext};
      if (file.is_relative()) file = model_.parent_path() / file;
      mesh::TriangleMesh mm;
      try {
        mm = mesh::ReadMesh(file);
      } catch (const InputError& e) {
        Warn("import (CSG line " + std::to_string(n.line) + "): " + e.what() + "; left out, as OpenSCAD leaves it out");
        return Solid();
      }
      Outside(file.string() + " (imported by " + model_.filename().string() + ")", Sha256Hex(n.canonical), mm);
      return MeshOf(Outward(std::move(mm)), m);
    }
    if (n.name == "surface") {
      auto f = n.args.find("file");
      fs::path file = f != n.args.end() && f->second.type == CsgValue::Type::kString ? f->second.text : "";
      if (file.is_relative()) file = model_.parent_path() / file;
      std::vector<std::string> warnings;
      const scad::HeightMap map = scad::ReadHeightMap(file, n.Boolean("invert", false), &warnings);
      for (const std::string& w : warnings) Warn("surface (CSG line " + std::to_string(n.line) + "): " + w);
      return MeshOf(scad::SurfaceMesh(map, n.Boolean("center", false)), m);
    }
    if (IsTwoD(n.name)) return Solid();    // 2D among 3D objects: ignored, as OpenSCAD ignores it
    if (n.name == "hull") return Solid();  // a hull of 2D children only
    throw NoNativeEquivalent{n.name};
  }

  OpenScadNodeContext& c_;
  fs::path model_, work_;
  bool mesh_road_ = true;
  std::string leaf_path_;  // the record path of the leaf MeshLeaf evaluates (its projections' children go below it)
  int projections_ = 0;
  int rendered_ = 0;
  bool linked_ = false;
  Render2 render2_;
};

// A temporary directory removed when it goes out of scope.
struct WorkDir {
  fs::path path;
  explicit WorkDir(const std::string& where) {
    char tmpl[] = "/tmp/fabatlas-openscad-XXXXXX";
    if (!::mkdtemp(tmpl)) throw DesignFault(where + ": cannot create a temporary directory for openscad");
    path = tmpl;
  }
  ~WorkDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

}  // namespace

namespace {

// Memory `t` holds: its own strings and meshes and its children's traces.
std::size_t TraceBytes(const SubtreeTrace& t) {
  std::size_t bytes = sizeof(SubtreeTrace) + t.topology.capacity() + t.op.capacity();
  for (const auto& c : t.children) bytes += sizeof(std::string) + c.capacity();
  for (const auto& c : t.child_paths) bytes += sizeof(std::string) + c.capacity();
  for (const auto& c : t.child_traces) bytes += sizeof(c) + (c ? TraceBytes(*c) : 0);
  for (const OutsideMesh& m : t.outside) {
    bytes += sizeof(OutsideMesh) + m.what.capacity() + m.key.capacity();
    if (m.mesh)
      bytes += sizeof(mesh::TriangleMesh) + m.mesh->vertices.capacity() * sizeof(m.mesh->vertices[0]) +
               m.mesh->triangles.capacity() * sizeof(m.mesh->triangles[0]);
  }
  return bytes;
}

}  // namespace

CachedSubtree EntryOf(Solid solid, std::shared_ptr<const SubtreeTrace> trace) {
  CachedSubtree entry;
  entry.solid = std::move(solid);
  if (trace && (!trace->op.empty() || !trace->outside.empty())) {
    entry.trace_bytes = TraceBytes(*trace);
    entry.trace = std::move(trace);
  }
  return entry;
}

void AppendDescendantRecords(const SubtreeTrace& trace, const std::string& path, std::vector<SubtreeRecord>* records) {
  for (std::size_t i = 0; i < trace.children.size() && i < trace.child_traces.size(); ++i) {
    const SubtreeTrace* child = trace.child_traces[i].get();
    if (!child || child->op.empty()) continue;  // found in a cache filled elsewhere: no record kept
    const std::string child_path = path + trace.child_paths[i];
    AppendDescendantRecords(*child, child_path, records);
    SubtreeRecord r;
    r.key = trace.children[i];
    r.topology = child->topology;
    r.path = child_path;
    r.op = child->op;
    r.from_cache = true;
    r.bytes = child->bytes;
    r.children = child->children;
    records->push_back(std::move(r));
  }
}

OpenScadNodeResult EvaluateOpenScadNode(const Node& node, const ResolvedArgs& args, const fs::path& dir,
                                        OpenScadNodeContext& context) {
  const fs::path model = dir / args.Text("file");
  // A job bundle is all a worker's evaluation reads: a model naming a file
  // outside its directory is refused before anything reads that file, here
  // as at submit (model_files.h).
  if (context.confine_model_files) {
    try {
      scad::ModelFiles(model);
    } catch (const InputError& e) {
      throw DesignFault(e.what());
    }
  }
  std::vector<std::pair<std::string, std::string>> overrides;
  if (auto it = args.values.find("set"); it != args.values.end())
    for (std::size_t i = 0; i < it->second.keys.size(); ++i)
      overrides.emplace_back(it->second.keys[i], it->second.literals[i]);
  WorkDir work(node.place.str());
  const std::string render = args.Text("render", "mesh");
  const bool native = render != "openscad";  // mesh (native) or levelset: fabatlas evaluates the CSG tree
  const fs::path out = work.path / (native ? "model.csg" : "model.stl");
  scad::OpenScadRun run;
  // The CSG tree from fabatlas's own evaluation of the model where it
  // implements the model's language (evaluate_model.h), else OpenSCAD's export.
  scad::ModelEvaluation own;
  if (native) own = scad::EvaluateModel(model, overrides);
  if (!own.bad_input.empty()) throw DesignFault(own.bad_input);
  if (!own.evaluated) {
    // OpenSCAD draws an unknown colour name in its default colour (a
    // warning --quiet hides); the designer meant a colour: bad input here too.
    std::ifstream in(model, std::ios::binary);
    std::stringstream text;
    text << in.rdbuf();
    if (const std::string bad = scad::UnknownColourName(text.str(), model.string()); !bad.empty())
      throw DesignFault(bad);
  }
  if (own.evaluated) {
    run.seconds = own.seconds;
  } else {
    try {
      if (!scad::RunOpenScad(model, out, overrides, &run)) {
        // A parser error is the model's, whatever the values: bad input
        // (one line naming the model and OpenSCAD's line, exit 2), where a
        // failure at these values only (an assert) fails the sample.
        const std::size_t parser = run.log_tail.find("Parser error");
        if (parser != std::string::npos) {
          std::string line;
          if (const std::size_t at = run.log_tail.rfind("line "); at != std::string::npos)
            line = ":" + run.log_tail.substr(at + 5, run.log_tail.find_first_not_of("0123456789", at + 5) - (at + 5));
          throw DesignFault(model.string() + line + ": OpenSCAD rejects the model: " + run.log_tail.substr(parser));
        }
        throw SampleFailure(kNoGeometry, node.place.str() + ": openscad failed: " + run.log_tail);
      }
    } catch (const SampleFailure&) {
      throw;
    } catch (const DesignFault&) {
      throw;
    } catch (const InputError& e) {
      throw DesignFault(node.place.str() + ": " + e.what());
    }
  }
  OpenScadNodeResult result;
  result.export_seconds = run.seconds;
  if (!native) {
    mesh::TriangleMesh m;
    try {
      m = mesh::ReadMesh(out);
    } catch (const InputError& e) {
      throw SampleFailure(kNoGeometry, node.place.str() + ": OpenSCAD's STL: " + e.what());
    }
    if (context.outside) {
      std::string key = Sha256Hex(args.Canonical());
      context.outside->push_back(
          {model.filename().string() + ": OpenSCAD's render", key, std::make_shared<const mesh::TriangleMesh>(m)});
    }
    result.solid = geometry::FromMesh(context.grid, m);
    return result;
  }
  std::string text = std::move(own.csg);
  if (!own.evaluated) {
    std::ifstream in(out, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    text = ss.str();
  }
  scad::CsgNode root;
  try {
    root = scad::ParseCsg(text, model.string() + " (OpenSCAD's CSG export)");
  } catch (const InputError& e) {
    throw SampleFailure(kNoGeometry, e.what());
  }
  CsgEvaluation evaluation(context, model, work.path, /*mesh_road=*/render != "levelset");
  CsgEvaluation::Result r = evaluation.Evaluate3(root, kIdentity, context.path + "/csg", /*need_solid=*/true);
  result.solid = r.solid;
  result.root_key = r.key;
  result.root_trace = r.trace;
  if (context.parts) context.parts->clear();
  if (context.parts && !result.solid.empty()) {
    // Each part evaluated apart (its subtrees keyed and cached as any), then
    // made disjoint from the parts before it; one part is the solid itself.
    const std::vector<scad::PartTree> trees = scad::PartTrees(root);
    int bodies = 0;
    std::map<int, int> regions;  // per body
    for (const auto& t : trees) {
      bodies = std::max(bodies, t.body);
      ++regions[t.body];
    }
    OpenScadNodeContext quiet = context;  // no records, warnings or outside meshes twice
    quiet.records = nullptr;
    quiet.outside = nullptr;
    quiet.warnings = nullptr;
    quiet.parts = nullptr;
    CsgEvaluation parts(quiet, model, work.path, /*mesh_road=*/render != "levelset");
    std::vector<Solid> earlier;
    for (const auto& t : trees) {
      Solid solid;
      if (trees.size() == 1) {
        solid = result.solid;
      } else {
        const scad::CsgNode part = scad::ParseCsg(t.csg, model.string() + " (part)");
        solid = parts.Evaluate3(part, kIdentity, context.path + "/part", /*need_solid=*/true).solid;
      }
      Solid own = parts.Minus(solid, earlier);
      if (!solid.empty()) earlier.push_back(std::move(solid));
      if (own.empty()) continue;
      Part p;
      p.name = "body" + std::to_string(t.body);
      if (regions[t.body] > 1) p.name += "-" + scad::HexColour(t.rgba).substr(1);
      p.coloured = t.coloured;
      p.rgba = t.rgba;
      p.mesh = own.ToMesh();
      if (!p.mesh.triangles.empty()) context.parts->push_back(std::move(p));
    }
  }
  return result;
}

}  // namespace fabatlas::design
