// A box around a CSG tree's solid without booleans (fabatlas/scad/csg_bounds.h).
#include "fabatlas/scad/csg_bounds.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

namespace fabatlas::scad {
namespace {

using Point = std::array<double, 3>;

// A node's extent: its box and whether it is a 2-D shape or a 3-D solid.
struct Extent {
  bool known = true;
  std::string unknown;
  bool empty = true;
  int dimension = 0;  // 2 or 3 when not empty
  Point lo{0, 0, 0}, hi{0, 0, 0};
};

Extent Unknown(const CsgNode& n, const std::string& why) {
  Extent e;
  e.known = false;
  e.unknown = std::to_string(n.line) + ": " + n.name + (why.empty() ? "" : " (" + why + ")");
  return e;
}

// The box of `points` (each 2 or 3 numbers) as a shape of `dimension`.
Extent BoxOf(const std::vector<Point>& points, int dimension) {
  Extent e;
  if (points.empty()) return e;
  e.empty = false;
  e.dimension = dimension;
  e.lo = e.hi = points[0];
  for (const Point& p : points)
    for (int k = 0; k < 3; ++k) {
      e.lo[k] = std::min(e.lo[k], p[k]);
      e.hi[k] = std::max(e.hi[k], p[k]);
    }
  return e;
}

std::vector<Point> Corners(const Extent& e) {
  std::vector<Point> c;
  for (int i = 0; i < 8; ++i)
    c.push_back({i & 1 ? e.hi[0] : e.lo[0], i & 2 ? e.hi[1] : e.lo[1], i & 4 ? e.hi[2] : e.lo[2]});
  return c;
}

// A vector argument of at least `count` finite numbers; false otherwise.
bool Numbers(const CsgValue& v, std::size_t count, std::vector<double>* out) {
  if (v.type != CsgValue::Type::kVector || v.items.size() < count) return false;
  out->clear();
  for (const CsgValue& x : v.items) {
    if (x.type != CsgValue::Type::kNumber || !std::isfinite(x.number)) return false;
    out->push_back(x.number);
  }
  return true;
}

const CsgValue* Arg(const CsgNode& n, const std::string& key) {
  auto it = n.args.find(key);
  return it == n.args.end() ? nullptr : &it->second;
}

// A `points` list of 2-D or 3-D points.
bool PointsOf(const CsgNode& n, int dimension, std::vector<Point>* out) {
  const CsgValue* points = Arg(n, "points");
  if (!points && !n.positional.empty()) points = &n.positional[0];
  if (!points || points->type != CsgValue::Type::kVector) return false;
  std::vector<double> xyz;
  for (const CsgValue& p : points->items) {
    if (!Numbers(p, dimension, &xyz)) return false;
    out->push_back({xyz[0], xyz[1], dimension == 3 ? xyz[2] : 0});
  }
  return true;
}

Extent Of(const CsgNode& n);

// The union of the children's boxes of the highest dimension among them
// (OpenSCAD 2021.01 leaves 2-D shapes out of a 3-D union).
Extent UnionOf(const std::vector<CsgNode>& children) {
  std::vector<Extent> parts;
  int dimension = 0;
  for (const CsgNode& c : children) {
    parts.push_back(Of(c));
    if (!parts.back().known) return parts.back();
    if (!parts.back().empty) dimension = std::max(dimension, parts.back().dimension);
  }
  std::vector<Point> corners;
  for (const Extent& p : parts)
    if (!p.empty && p.dimension == dimension) corners.insert(corners.end(), {p.lo, p.hi});
  return BoxOf(corners, dimension);
}

Extent IntersectionOf(const std::vector<CsgNode>& children) {
  Extent box;
  for (std::size_t i = 0; i < children.size(); ++i) {
    Extent c = Of(children[i]);
    if (!c.known || c.empty) return c;
    if (i == 0) {
      box = c;
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      box.lo[k] = std::max(box.lo[k], c.lo[k]);
      box.hi[k] = std::min(box.hi[k], c.hi[k]);
      if (box.lo[k] > box.hi[k]) return Extent{};  // disjoint: nothing
    }
  }
  return box;
}

Extent MinkowskiOf(const std::vector<CsgNode>& children) {
  Extent sum;
  for (std::size_t i = 0; i < children.size(); ++i) {
    Extent c = Of(children[i]);
    if (!c.known || c.empty) return c;
    if (i == 0) {
      sum = c;
      continue;
    }
    sum.dimension = std::max(sum.dimension, c.dimension);
    for (int k = 0; k < 3; ++k) {
      sum.lo[k] += c.lo[k];
      sum.hi[k] += c.hi[k];
    }
  }
  return sum;
}

// multmatrix(m): the box of the child's corners mapped by the 4x4 matrix.
Extent Transformed(const CsgNode& n) {
  Extent child = UnionOf(n.children);
  if (!child.known || child.empty) return child;
  const CsgValue* m = Arg(n, "m");
  if (!m && !n.positional.empty()) m = &n.positional[0];
  if (!m || m->type != CsgValue::Type::kVector || m->items.size() < 3) return Unknown(n, "no 4x4 matrix");
  std::vector<std::vector<double>> rows(3);
  for (int r = 0; r < 3; ++r)
    if (!Numbers(m->items[r], 4, &rows[r])) return Unknown(n, "a row of fewer than 4 numbers");
  double w = 1;  // a last row (0, 0, 0, w) scales by 1/w, as OpenSCAD applies it to homogeneous points
  std::vector<double> last;
  if (m->items.size() >= 4 && Numbers(m->items[3], 4, &last)) {
    if (last[0] != 0 || last[1] != 0 || last[2] != 0 || last[3] == 0) return Unknown(n, "a projective matrix");
    w = last[3];
  }
  std::vector<Point> mapped;
  for (const Point& p : Corners(child)) {
    Point q;
    for (int r = 0; r < 3; ++r) q[r] = (rows[r][0] * p[0] + rows[r][1] * p[1] + rows[r][2] * p[2] + rows[r][3]) / w;
    mapped.push_back(q);
  }
  return BoxOf(mapped, child.dimension);
}

// Largest distance from the z axis of the xy box's corners.
double Reach(const Extent& e) {
  return std::hypot(std::max(std::abs(e.lo[0]), std::abs(e.hi[0])), std::max(std::abs(e.lo[1]), std::abs(e.hi[1])));
}

Extent LinearExtrude(const CsgNode& n) {
  Extent outline = UnionOf(n.children);
  if (!outline.known || outline.empty) return outline;
  const double h = n.Number("height", 100);
  const bool center = n.Boolean("center", false);
  std::vector<double> scale{1, 1};
  if (const CsgValue* s = Arg(n, "scale"); s && s->type == CsgValue::Type::kNumber)
    scale = {s->number, s->number};
  else if (s && !Numbers(*s, 2, &scale))
    return Unknown(n, "a scale that is not a number or [x, y]");
  // The top outline is the bottom one scaled about the origin.
  Extent top = outline;
  for (int k = 0; k < 2; ++k) {
    top.lo[k] = std::min(outline.lo[k] * scale[k], outline.hi[k] * scale[k]);
    top.hi[k] = std::max(outline.lo[k] * scale[k], outline.hi[k] * scale[k]);
  }
  Extent e = BoxOf({outline.lo, outline.hi, top.lo, top.hi}, 3);
  if (n.Number("twist", 0) != 0) {  // the outline turns about the z axis
    const double r = std::max(Reach(outline), Reach(top));
    e.lo[0] = e.lo[1] = -r;
    e.hi[0] = e.hi[1] = r;
  }
  e.lo[2] = center ? -h / 2 : 0;
  e.hi[2] = center ? h / 2 : h;
  return e;
}

// rotate_extrude: the outline's x >= 0 part swept about z, bounded by a full turn.
Extent RotateExtrude(const CsgNode& n) {
  Extent outline = UnionOf(n.children);
  if (!outline.known || outline.empty) return outline;
  const double r = std::max(std::abs(outline.lo[0]), std::abs(outline.hi[0]));
  return BoxOf({{-r, -r, outline.lo[1]}, {r, r, outline.hi[1]}}, 3);
}

Extent Offset(const CsgNode& n) {
  Extent e = UnionOf(n.children);
  if (!e.known || e.empty) return e;
  const double grow = std::max(0.0, Arg(n, "r") ? n.Number("r", 0) : n.Number("delta", 0));
  for (int k = 0; k < 2; ++k) {
    e.lo[k] -= grow;
    e.hi[k] += grow;
  }
  return e;
}

Extent Of(const CsgNode& n) {
  const std::string& name = n.name;
  static const std::set<std::string> kUnions = {"group", "union", "hull", "color", "render"};
  if (kUnions.count(name)) return UnionOf(n.children);
  if (name == "difference") return n.children.empty() ? Extent{} : Of(n.children[0]);
  if (name == "intersection") return IntersectionOf(n.children);
  if (name == "minkowski") return MinkowskiOf(n.children);
  if (name == "multmatrix") return Transformed(n);
  if (name == "linear_extrude") return LinearExtrude(n);
  if (name == "rotate_extrude") return RotateExtrude(n);
  if (name == "offset") return Offset(n);
  if (name == "projection") {
    Extent e = UnionOf(n.children);
    e.lo[2] = e.hi[2] = 0;
    if (!e.empty) e.dimension = 2;
    return e;
  }
  std::vector<double> size;
  if (name == "cube" || name == "square") {
    const int d = name == "cube" ? 3 : 2;
    const CsgValue* s = Arg(n, "size");
    if (s && s->type == CsgValue::Type::kNumber) size.assign(d, s->number);
    if (s && s->type == CsgValue::Type::kVector && !Numbers(*s, d, &size)) return Unknown(n, "malformed size");
    if (!s) size.assign(d, 1);
    if (size.size() == 2) size.push_back(0);
    Point lo{0, 0, 0}, hi{size[0], size[1], size[2]};
    if (n.Boolean("center", false))
      for (int k = 0; k < d; ++k) lo[k] = -(hi[k] /= 2);
    return BoxOf({lo, hi}, d);
  }
  if (name == "sphere") {
    const double r = std::abs(n.Number("r", 1));
    return BoxOf({{-r, -r, -r}, {r, r, r}}, 3);
  }
  if (name == "circle") {
    const double r = std::abs(n.Number("r", 1));
    return BoxOf({{-r, -r, 0}, {r, r, 0}}, 2);
  }
  if (name == "cylinder") {
    const double h = n.Number("h", 1), r = std::max(std::abs(n.Number("r1", 1)), std::abs(n.Number("r2", 1)));
    const double z0 = n.Boolean("center", false) ? -h / 2 : 0;
    return BoxOf({{-r, -r, z0}, {r, r, z0 + h}}, 3);
  }
  if (name == "polyhedron" || name == "polygon") {
    const int d = name == "polyhedron" ? 3 : 2;
    std::vector<Point> points;
    if (!PointsOf(n, d, &points)) return Unknown(n, "malformed points");
    return BoxOf(points, d);
  }
  return Unknown(n, "");  // import, surface, text, resize, ...: the extent is not in the arguments
}

}  // namespace

CsgBox CsgBounds(const CsgNode& root) {
  const Extent e = Of(root);
  CsgBox box;
  box.known = e.known;
  box.unknown = e.unknown;
  box.empty = !e.known || e.empty || e.dimension != 3;
  if (!box.empty) {
    box.lo = e.lo;
    box.hi = e.hi;
  }
  return box;
}

}  // namespace fabatlas::scad
