// OpenSCAD 2021.01's 2-D subtrees (fabatlas/scad/evaluate_2d.h): the walk
// over the CSG tree, each node as OpenSCAD's GeometryEvaluator computes it.
#include "fabatlas/scad/evaluate_2d.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/convex_hull_2.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "clipper_shape.h"
#include "evaluate_2d_internal.h"
#include "fabatlas/error.h"

namespace fabatlas::scad {
namespace {

using internal::Shape;
namespace fs = std::filesystem;

std::string Where(const CsgNode& n) { return n.name + " (CSG line " + std::to_string(n.line) + ")"; }

void Warn(std::vector<std::string>* warnings, const std::string& line) {
  if (warnings) warnings->push_back(line);
}

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string ImportExtension(const CsgNode& n) {
  auto it = n.args.find("file");
  if (it == n.args.end() || it->second.type != CsgValue::Type::kString) return "";
  return Lower(fs::path(it->second.text).extension().string());
}

const CsgValue* Arg(const CsgNode& n, const std::string& key) {
  auto it = n.args.find(key);
  return it == n.args.end() ? nullptr : &it->second;
}

std::string Echo(const CsgValue& v) {
  if (v.type == CsgValue::Type::kNumber) {
    if (std::isnan(v.number)) return "nan";
    if (std::isinf(v.number)) return v.number > 0 ? "inf" : "-inf";
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v.number);
    return buf;
  }
  if (v.type == CsgValue::Type::kVector) {
    std::string s = "[";
    for (std::size_t i = 0; i < v.items.size(); ++i) s += (i ? ", " : "") + Echo(v.items[i]);
    return s + "]";
  }
  if (v.type == CsgValue::Type::kBoolean) return v.boolean ? "true" : "false";
  if (v.type == CsgValue::Type::kString) return "\"" + v.text + "\"";
  return "undef";
}

class Evaluator {
 public:
  Evaluator(const Evaluate2dOptions& o, std::vector<std::string>* w) : o_(o), w_(w) {}

  // nullopt: no geometry (OpenSCAD's nullptr), as an empty group gives.
  std::optional<Shape> Eval(const CsgNode& n) {
    const std::string& name = n.name;
    if (name == "circle") return Circle(n);
    if (name == "square") return Square(n);
    if (name == "polygon") return PolygonNode(n);
    if (name == "multmatrix") return Transform(n);
    if (name == "group" || name == "union" || name == "render" || name == "color")
      return Combine(n, ClipperLib::ctUnion, true);
    if (name == "difference") return Combine(n, ClipperLib::ctDifference, true);
    if (name == "intersection") return Combine(n, ClipperLib::ctIntersection, true);
    if (name == "offset") return OffsetNode(n);
    if (name == "hull") return Hull(n);
    if (name == "minkowski") return internal::Minkowski(Pointers(Children(n, true)));
    if (name == "resize") return Resize(n);
    if (name == "projection") return Projection(n);
    if (name == "text") return Outline(n);
    if (name == "import") return Import(n);
    throw NoNativeEquivalentError(Where(n) + ": no native 2-D evaluation of " + name);
  }

  // The children's geometries as OpenSCAD collects them for a 2-D
  // operation: 3-D children ignored with its warning, empty ones null.
  std::vector<std::optional<Shape>> Children(const CsgNode& n, bool mixing_check) {
    std::vector<std::optional<Shape>> out;
    bool mixed = false;
    for (const CsgNode& c : n.children) {
      const int dim = Dimension(c);
      if (dim == 3) {
        if (mixing_check && !mixed) Warn(w_, "WARNING: Mixing 2D and 3D objects is not supported, " + Where(c));
        mixed = true;
        Warn(w_, "WARNING: Ignoring 3D child object for 2D operation, " + Where(c));
        out.emplace_back();
        continue;
      }
      if (dim == 0) {
        out.emplace_back();
        continue;
      }
      std::optional<Shape> s = Eval(c);
      if (s && s->loops.empty()) s.reset();
      out.push_back(std::move(s));
    }
    return out;
  }

  static std::vector<const Shape*> Pointers(const std::vector<std::optional<Shape>>& shapes) {
    std::vector<const Shape*> p;
    for (const auto& s : shapes) p.push_back(s ? &*s : nullptr);
    return p;
  }

  // OpenSCAD's applyToChildren2D: no children, nothing; one, a copy (not
  // passed through Clipper); more, the boolean.
  std::optional<Shape> Combine(const CsgNode& n, ClipperLib::ClipType op, bool mixing_check) {
    std::vector<std::optional<Shape>> children = Children(n, mixing_check);
    if (children.empty()) return std::nullopt;
    if (children.size() == 1) return children[0];
    return internal::Clip(Pointers(children), op, w_);
  }

 private:
  int Fragments(const CsgNode& n, double r) const {
    return scad::Fragments(r, n.Number("$fn", 0), n.Number("$fs", 2), n.Number("$fa", 12));
  }

  Shape Circle(const CsgNode& n) {
    const double r = n.Number("r", 1);
    Shape s;
    if (r > 0 && !std::isinf(r)) s.loops.push_back(CircleLoop(r, Fragments(n, r)));
    return s;
  }

  Shape Square(const CsgNode& n) {
    double x = 1, y = 1;
    if (const CsgValue* size = Arg(n, "size")) {
      if (size->type == CsgValue::Type::kVector && size->items.size() >= 2) {
        x = size->items[0].number;
        y = size->items[1].number;
      } else if (size->type == CsgValue::Type::kNumber) {
        x = y = size->number;
      }
    }
    Shape s;
    if (x > 0 && y > 0 && !std::isinf(x) && !std::isinf(y))
      s.loops.push_back(SquareLoop(x, y, n.Boolean("center", false)));
    return s;
  }

  // polygon(points, paths): a point that is not two finite numbers empties
  // the polygon (OpenSCAD's error); a NaN coordinate, which OpenSCAD passes
  // to Clipper as an undefined integer, drops its point here (warned); path
  // indices out of range are skipped (warned). Loops filled even-odd.
  Shape PolygonNode(const CsgNode& n) {
    Shape s;
    s.sanitized = false;
    const CsgValue* points = Arg(n, "points");
    if (!points) return s;
    std::vector<Point2> pts;
    std::vector<bool> nan;
    for (std::size_t i = 0; i < points->items.size(); ++i) {
      const CsgValue& p = points->items[i];
      const bool pair = p.type == CsgValue::Type::kVector && p.items.size() == 2 &&
                        p.items[0].type == CsgValue::Type::kNumber && p.items[1].type == CsgValue::Type::kNumber;
      if (!pair || std::isinf(p.items[0].number) || std::isinf(p.items[1].number)) {
        Warn(w_, "ERROR: Unable to convert points[" + std::to_string(i) + "] = " + Echo(p) + " to a vec2 of numbers, " +
                     Where(n));
        return Shape{};
      }
      pts.push_back({p.items[0].number, p.items[1].number});
      nan.push_back(std::isnan(pts.back()[0]) || std::isnan(pts.back()[1]));
      if (nan.back())
        Warn(w_, "WARNING: points[" + std::to_string(i) + "] = " + Echo(p) +
                     " is not a number; the point is dropped, " + Where(n));
    }
    auto keep = [&](std::size_t i, Loop& loop) {
      if (!nan[i]) loop.push_back(pts[i]);
    };
    const CsgValue* paths = Arg(n, "paths");
    if (!paths || paths->type != CsgValue::Type::kVector || paths->items.empty()) {
      if (pts.size() > 2) {
        Loop loop;
        for (std::size_t i = 0; i < pts.size(); ++i) keep(i, loop);
        s.loops.push_back(std::move(loop));
      }
    } else {
      for (std::size_t k = 0; k < paths->items.size(); ++k) {
        Loop loop;
        const CsgValue& path = paths->items[k];
        for (std::size_t j = 0; j < path.items.size(); ++j) {
          const double v = path.items[j].type == CsgValue::Type::kNumber ? path.items[j].number : -1;
          // OpenSCAD converts the index to an unsigned integer.
          const bool in_range = v >= 0 && v < static_cast<double>(pts.size());
          if (in_range) {
            keep(static_cast<std::size_t>(v), loop);
          } else {
            Warn(w_, "WARNING: Point index " + Echo(path.items[j]) + " is out of bounds (from paths[" +
                         std::to_string(k) + "][" + std::to_string(j) + "]), " + Where(n));
          }
        }
        s.loops.push_back(std::move(loop));
      }
    }
    return internal::Sanitize(s, w_);
  }

  // multmatrix of 2-D children: their union mapped by the matrix's x/y part;
  // a singular map removes the shape, a mirroring one re-sanitizes it.
  std::optional<Shape> Transform(const CsgNode& n) {
    const CsgValue* m = Arg(n, "m");
    if (!m && !n.positional.empty()) m = &n.positional[0];
    if (!m || m->items.size() < 2 || m->items[0].items.size() < 4 || m->items[1].items.size() < 4)
      throw NoNativeEquivalentError(Where(n) + ": multmatrix without a 4x4 matrix");
    for (const CsgValue& row : m->items)
      for (const CsgValue& x : row.items)
        if (x.type == CsgValue::Type::kNumber && !std::isfinite(x.number)) {
          Warn(w_,
               "WARNING: Transformation matrix contains Not-a-Number and/or Infinity - removing object., " + Where(n));
          return std::nullopt;
        }
    auto at = [&](int r, int c) { return m->items[r].items[c].number; };
    const double a = at(0, 0), b = at(0, 1), tx = at(0, 3), c = at(1, 0), d = at(1, 1), ty = at(1, 3);
    std::optional<Shape> s = Combine(n, ClipperLib::ctUnion, true);
    if (!s) return s;
    const double det = a * d - b * c;
    if (det == 0) {
      Warn(w_, "WARNING: Scaling a 2D object with 0 - removing object, " + Where(n));
      s->loops.clear();
    }
    for (Loop& loop : s->loops)
      for (Point2& p : loop) p = {a * p[0] + b * p[1] + tx, c * p[0] + d * p[1] + ty};
    if (s->sanitized && det <= 0) {
      Shape turned = *s;
      return internal::Sanitize(turned, w_);
    }
    return s;
  }

  // offset(r) rounds with Clipper's arc tolerance from the fragments of a
  // circle of radius |r|; offset(delta) mitres (limit 10^6, so never
  // squared), chamfer = true squares the corners.
  std::optional<Shape> OffsetNode(const CsgNode& n) {
    double delta = 1;
    ClipperLib::JoinType join = ClipperLib::jtRound;
    const CsgValue* r = Arg(n, "r");
    const CsgValue* d = Arg(n, "delta");
    if (r && r->type == CsgValue::Type::kNumber) {
      delta = r->number;
    } else if (d && d->type == CsgValue::Type::kNumber) {
      delta = d->number;
      join = n.Boolean("chamfer", false) ? ClipperLib::jtSquare : ClipperLib::jtMiter;
    }
    std::optional<Shape> s = Combine(n, ClipperLib::ctUnion, false);
    if (!s) return s;
    if (!std::isfinite(delta)) return Shape{};  // OpenSCAD's result is empty
    const int fragments = Fragments(n, std::abs(delta));
    const double arc_tolerance = std::abs(delta) * (1 - CosDegrees(180.0 / fragments));
    return internal::Offset(*s, delta, join, 1000000.0, arc_tolerance);
  }

  // hull: the convex hull of every vertex of the children (not through
  // Clipper, so its vertices are the children's own).
  Shape Hull(const CsgNode& n) {
    using K = CGAL::Exact_predicates_inexact_constructions_kernel;
    std::vector<K::Point_2> points, hull;
    for (const auto& s : Children(n, true))
      if (s)
        for (const Loop& loop : s->loops)
          for (const Point2& p : loop) points.emplace_back(p[0], p[1]);
    CGAL::convex_hull_2(points.begin(), points.end(), std::back_inserter(hull));
    Shape out;
    out.sanitized = false;
    if (hull.size() >= 3) {
      Loop loop;
      for (const auto& p : hull) loop.push_back({p.x(), p.y()});
      out.loops.push_back(std::move(loop));
    }
    return out;
  }

  // resize(newsize, auto): the union scaled about the origin so that its
  // bounding box gets the new size (0 keeps an axis, or scales it with the
  // largest given axis where auto says so).
  std::optional<Shape> Resize(const CsgNode& n) {
    std::optional<Shape> s = Combine(n, ClipperLib::ctUnion, true);
    if (!s || s->loops.empty()) return s;
    double size[2] = {0, 0};
    bool autosize[2] = {false, false};
    if (const CsgValue* v = Arg(n, "newsize"))
      for (std::size_t i = 0; i < 2 && i < v->items.size(); ++i) size[i] = v->items[i].number;
    if (const CsgValue* v = Arg(n, "auto")) {
      if (v->type == CsgValue::Type::kBoolean) autosize[0] = autosize[1] = v->boolean;
      for (std::size_t i = 0; i < 2 && i < v->items.size(); ++i)
        autosize[i] = v->items[i].type == CsgValue::Type::kBoolean ? v->items[i].boolean : v->items[i].number != 0;
    }
    Point2 lo{HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL};
    for (const Loop& loop : s->loops)
      for (const Point2& p : loop)
        for (int k = 0; k < 2; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
    const double extent[2] = {hi[0] - lo[0], hi[1] - lo[1]};
    const int maxdim = (size[1] != 0 && size[1] > size[0]) ? 1 : 0;
    const double scale[2] = {size[0] > 0 ? size[0] / extent[0] : 1, size[1] > 0 ? size[1] / extent[1] : 1};
    const double autoscale = size[maxdim] > 0 ? size[maxdim] / extent[maxdim] : 1;
    double f[2];
    for (int k = 0; k < 2; ++k) f[k] = (!autosize[k] || size[k] > 0) ? scale[k] : autoscale;
    if (f[0] * f[1] == 0) {
      Warn(w_, "WARNING: Scaling a 2D object with 0 - removing object, " + Where(n));
      s->loops.clear();
    }
    for (Loop& loop : s->loops)
      for (Point2& p : loop) p = {f[0] * p[0], f[1] * p[1]};
    return s;
  }

  // projection: cut = false, the shadow of each 3-D child; cut = true, where
  // the children's union meets z = 0. 2-D children are ignored (with
  // OpenSCAD's warning for cut = true, silently otherwise, as it does).
  std::optional<Shape> Projection(const CsgNode& n) {
    const bool cut = n.Boolean("cut", false);
    std::vector<mesh::TriangleMesh> meshes;
    for (const CsgNode& c : n.children) {
      const int dim = Dimension(c);
      if (dim == 2 && cut) Warn(w_, "WARNING: Ignoring 2D child object for 3D operation, " + Where(c));
      if (dim != 3) continue;
      if (!o_.mesh3d) throw NoNativeEquivalentError(Where(n) + ": projection needs the 3-D child's mesh (no mesh3d)");
      meshes.push_back(o_.mesh3d(c));
    }
    if (meshes.empty()) return std::nullopt;
    Shape s = cut ? internal::Section(meshes) : internal::Shadow(meshes);
    if (s.loops.empty()) return std::nullopt;
    return s;
  }

  // A node whose outline only a callback can give (text, 2-D imports):
  // its loops filled even-odd, through Clipper like OpenSCAD's own.
  Shape Outline(const CsgNode& n) {
    if (!o_.outline)
      throw NoNativeEquivalentError(Where(n) + ": no native 2-D evaluation of " + n.name + " (no outline)");
    Shape s{o_.outline(n), false};
    return internal::Sanitize(s, w_);
  }

  Shape Import(const CsgNode& n) {
    const std::string ext = ImportExtension(n);
    if (ext != ".dxf" && ext != ".svg")
      throw NoNativeEquivalentError(Where(n) + ": import of a 3-D file in a 2-D subtree");
    const std::string file = Arg(n, "file")->text;
    fs::path path = file;
    if (path.is_relative()) path = o_.model_dir / path;
    const fs::path dir = fs::weakly_canonical(o_.model_dir.empty() ? fs::current_path() : o_.model_dir);
    const fs::path resolved = fs::weakly_canonical(path);
    const auto [end, unused] = std::mismatch(dir.begin(), dir.end(), resolved.begin(), resolved.end());
    if (end != dir.end())
      throw InputError(Where(n) + ": import(\"" + file + "\") is outside the model's directory " + dir.string());
    return Outline(n);
  }

  const Evaluate2dOptions& o_;
  std::vector<std::string>* w_;
};

Polygon2d ToPolygon(const std::optional<Shape>& s) {
  Polygon2d p;
  if (!s) return p;
  for (Loop loop : s->loops) {
    if (loop.size() < 3) continue;
    if (!s->sanitized) {  // a hull or a leaf's own loop: counter-clockwise
      double area = 0;
      for (std::size_t i = 0; i < loop.size(); ++i) {
        const Point2& a = loop[i];
        const Point2& b = loop[(i + 1) % loop.size()];
        area += a[0] * b[1] - b[0] * a[1];
      }
      if (area < 0) std::reverse(loop.begin(), loop.end());
    }
    p.loops.push_back(std::move(loop));
  }
  return p;
}

}  // namespace

int Dimension(const CsgNode& n) {
  const std::string& name = n.name;
  if (name == "circle" || name == "square" || name == "polygon" || name == "text" || name == "offset" ||
      name == "projection")
    return 2;
  if (name == "import") {
    const std::string ext = ImportExtension(n);
    return ext == ".dxf" || ext == ".svg" ? 2 : 3;
  }
  if (name == "cube" || name == "sphere" || name == "cylinder" || name == "polyhedron" || name == "linear_extrude" ||
      name == "rotate_extrude" || name == "surface")
    return 3;
  for (const CsgNode& c : n.children)
    if (const int d = Dimension(c)) return d;
  return 0;
}

Polygon2d Evaluate2d(const CsgNode& node, const Evaluate2dOptions& options, std::vector<std::string>* warnings) {
  Evaluator e(options, warnings);
  return ToPolygon(e.Eval(node));
}

namespace internal {

Polygon2d UnionOfChildren(const CsgNode& node, const Evaluate2dOptions& options, std::vector<std::string>* warnings) {
  Evaluator e(options, warnings);
  return ToPolygon(e.Combine(node, ClipperLib::ctUnion, false));
}

}  // namespace internal
}  // namespace fabatlas::scad
