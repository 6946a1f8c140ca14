// linear_extrude and rotate_extrude of 2-D children as OpenSCAD 2021.01
// builds them (fabatlas/scad/evaluate_2d.h).
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "evaluate_2d_internal.h"
#include "fabatlas/scad/evaluate_2d.h"
#include "fabatlas/scad/region_outline.h"

namespace fabatlas::scad {
namespace {

void RefuseFile(const CsgNode& n) {
  auto it = n.args.find("file");
  if (it != n.args.end() && it->second.type == CsgValue::Type::kString && !it->second.text.empty())
    throw NoNativeEquivalentError(n.name + " (CSG line " + std::to_string(n.line) + "): no native " + n.name +
                                  " of a file");
}

bool InsideEvenOdd(const std::vector<Loop>& loops, const Point2& p) {
  bool inside = false;
  for (const Loop& loop : loops)
    for (std::size_t i = 0, j = loop.size() - 1; i < loop.size(); j = i++) {
      const Point2& a = loop[i];
      const Point2& b = loop[j];
      if ((a[1] > p[1]) != (b[1] > p[1]) && p[0] < (b[0] - a[0]) * (p[1] - a[1]) / (b[1] - a[1]) + a[0])
        inside = !inside;
    }
  return inside;
}

// The polygon's loops and the triangulation of its inside.
Region2 RegionOf(const Polygon2d& p) {
  return ResolveRegion(p.loops, [&](const Point2& q) { return InsideEvenOdd(p.loops, q); });
}

double Finite(const CsgNode& n, const std::string& key, double fallback) {
  const double v = n.Number(key, fallback);
  return std::isfinite(v) ? v : fallback;
}

}  // namespace

mesh::TriangleMesh LinearExtrude(const CsgNode& n, const Evaluate2dOptions& options,
                                 std::vector<std::string>* warnings) {
  RefuseFile(n);
  // OpenSCAD's argument rules: height 100 unless a finite number, <= 0 an
  // empty solid; scale a number or [x, y], negative taken as 0; slices used
  // when > 0.
  const double height = Finite(n, "height", 100);
  const bool center = n.Boolean("center", false);
  const double twist = Finite(n, "twist", 0);
  const int slices_arg = static_cast<int>(Finite(n, "slices", 0));
  Point2 scale{1, 1};
  if (auto it = n.args.find("scale"); it != n.args.end()) {
    const CsgValue& v = it->second;
    if (v.type == CsgValue::Type::kNumber && std::isfinite(v.number)) {
      scale = {v.number, v.number};
    } else if (v.type == CsgValue::Type::kVector && v.items.size() == 2 && std::isfinite(v.items[0].number) &&
               std::isfinite(v.items[1].number)) {
      scale = {v.items[0].number, v.items[1].number};
    }
  }
  scale = {std::max(scale[0], 0.0), std::max(scale[1], 0.0)};
  const Polygon2d polygon = internal::UnionOfChildren(n, options, warnings);
  if (polygon.loops.empty() || height <= 0) return {};
  double r_sqr = 0, delta_sqr = 0;
  for (const Loop& loop : polygon.loops)
    for (const Point2& p : loop) {
      r_sqr = std::max(r_sqr, p[0] * p[0] + p[1] * p[1]);
      const double dx = p[0] - p[0] * scale[0], dy = p[1] - p[1] * scale[1];
      delta_sqr = std::max(delta_sqr, dx * dx + dy * dy);
    }
  const int slices = slices_arg > 0 ? slices_arg
                                    : ExtrudeSlices(r_sqr, delta_sqr, height, twist, scale, n.Number("$fn", 0),
                                                    n.Number("$fs", 2), n.Number("$fa", 12));
  const Region2 region = RegionOf(polygon);
  if (region.triangles.empty()) return {};
  return LinearExtrudeMesh(region, height, center, twist, slices, scale);
}

mesh::TriangleMesh RotateExtrude(const CsgNode& n, const Evaluate2dOptions& options,
                                 std::vector<std::string>* warnings) {
  RefuseFile(n);
  double angle = Finite(n, "angle", 360);
  if (angle <= -360 || angle > 360) angle = 360;
  const Polygon2d polygon = internal::UnionOfChildren(n, options, warnings);
  if (polygon.loops.empty() || angle == 0) return {};
  // OpenSCAD scans the points in order and stops at the first that puts
  // points on both sides of the axis (the range it reports is the range so far).
  double min_x = 0, max_x = 0;
  for (const Loop& loop : polygon.loops)
    for (const Point2& p : loop) {
      min_x = std::min(min_x, p[0]);
      max_x = std::max(max_x, p[0]);
      if (max_x - min_x > max_x && max_x - min_x > std::abs(min_x)) {
        char line[200];
        std::snprintf(
            line, sizeof line,
            "ERROR: all points for rotate_extrude() must have the same X coordinate sign (range is %.2f -> %.2f)",
            min_x, max_x);
        if (warnings) warnings->push_back(line);
        return {};
      }
    }
  const int fragments = static_cast<int>(std::max(
      Fragments(max_x - min_x, n.Number("$fn", 0), n.Number("$fs", 2), n.Number("$fa", 12)) * std::abs(angle) / 360,
      1.0));
  const Region2 region = RegionOf(polygon);
  if (region.triangles.empty()) return {};
  return RotateExtrudeMesh(region, angle, fragments);
}

}  // namespace fabatlas::scad
