// 2D subtrees of OpenSCAD's CSG tree as shapes (csg_shape_2d.h).
#include "csg_shape_2d.h"

#include <algorithm>
#include <limits>
#include <memory>

#include "convex_hull_2d.h"
#include "csg_affine.h"
#include "fabatlas/scad/region_distance.h"

namespace fabatlas::design::csg {

bool PointInLoop(const scad::Point2& p, const Loop& loop) {
  bool inside = false;
  for (std::size_t i = 0, j = loop.size() - 1; i < loop.size(); j = i++) {
    const auto& a = loop[i];
    const auto& b = loop[j];
    if ((a[1] > p[1]) != (b[1] > p[1]) && p[0] < (b[0] - a[0]) * (p[1] - a[1]) / (b[1] - a[1]) + a[0]) inside = !inside;
  }
  return inside;
}

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

Loop Apply(const Affine2& t, const Loop& l) {
  Loop out;
  for (const auto& p : l) out.push_back({t[0] * p[0] + t[1] * p[1] + t[2], t[3] * p[0] + t[4] * p[1] + t[5]});
  return out;
}

namespace {

// polygon(points, paths) under t: its paths as loops, else its points as one.
Shape2 Polygon2(const CsgNode& n, const Affine2& t) {
  Shape2 s;
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

}  // namespace

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
  if (name == "polygon") return Polygon2(n, t);
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

}  // namespace fabatlas::design::csg
