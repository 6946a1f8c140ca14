// The checks of a sample's solid and its surface: watertight, min_thickness,
// stands and max_volume (docs/design-format.md, checks; docs/mesh.md, "Which
// check runs where").

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>

#include "check_kinds.h"
#include "checks.h"
#include "convex_hull_2d.h"
#include "fabatlas/error.h"
#include "fabatlas/geometry/folded_triangles.h"
#include "fabatlas/mesh/mesh_report.h"
#include "fabatlas/mesh/shape_diameter.h"

namespace fabatlas::design {
namespace {

std::string Mm(double v) {
  std::ostringstream s;
  s.precision(3);
  s << v << " mm";
  return s.str();
}

double Cross(const geometry::Vec2& o, const geometry::Vec2& a, const geometry::Vec2& b) {
  return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

}  // namespace

namespace check {

// Watertight, manifold, not self-intersecting — checked where it can fail:
//  - every mesh that came from outside fabatlas (a mesh node's file, an
//    OpenSCAD polyhedron or render) gets the full test (CGAL, with
//    self-intersections), its defects named; reports are remembered per
//    mesh content for the process, so a mesh is inspected once;
//  - a mesh solid's boundary (the mesh road of OpenSCAD models: exact
//    booleans of the model's own faces, rounded to doubles; Nef results
//    where two parts share only an edge) gets the full test too: it can be
//    non-manifold, and rounding can make it touch itself;
//  - the sample's own level-set extraction is closed and manifold by
//    construction, so what it gets is the cheap test of what it can get
//    wrong: no triangle folded against the level set's outward direction
//    where a part is thinner than a voxel (geometry/folded_triangles.h;
//    docs/mesh.md, "Which check runs where").
CheckOutcome Watertight(CheckContext& c) {
  CheckOutcome o;
  o.passed = true;
  if (c.outside) {
    static std::mutex mutex;
    static std::map<std::string, mesh::MeshReport> reports;
    for (const OutsideMesh& m : *c.outside) {
      mesh::MeshReport report;
      bool known = false;
      {
        std::lock_guard<std::mutex> lock(mutex);
        auto it = reports.find(m.key);
        if (it != reports.end()) {
          report = it->second;
          known = true;
        }
      }
      if (!known) {
        report = mesh::InspectMesh(*m.mesh);
        std::lock_guard<std::mutex> lock(mutex);
        if (reports.size() < 100000) reports[m.key] = report;
      }
      if (!report.closed || !report.manifold || report.self_intersecting) {
        o.passed = false;
        o.failure = !report.closed || !report.manifold ? kNotWatertight : kSelfIntersecting;
        o.reason = m.what + ": " + report.Reasons();
        return o;
      }
    }
  }
  if (const mesh::TriangleMesh* boundary = c.solid().boundary()) {
    const mesh::MeshReport report = mesh::InspectMesh(*boundary);
    if (!report.closed || !report.manifold || report.self_intersecting) {
      o.passed = false;
      o.failure = !report.closed || !report.manifold ? kNotWatertight : kSelfIntersecting;
      o.reason = "the model's exact surface: " + report.Reasons();
    }
    return o;
  }
  // Folds covering less than one voxel face (a single triangle at the tip of
  // a sharp wedge) are below what the grid resolves at all; more is a part
  // the sample's surface does not represent.
  const geometry::FoldedTriangles folds = geometry::FindFoldedTriangles(c.solid(), c.Mesh());
  const double voxel = c.solid().voxel_size();
  if (folds.area > voxel * voxel) {
    char where[200];
    std::snprintf(where, sizeof where,
                  "first near (%.4g, %.4g, %.4g) mm): a part there is thinner than a voxel (%g mm)", folds.first[0],
                  folds.first[1], folds.first[2], voxel);
    o.passed = false;
    o.failure = kThinParts;  // the model's cause; the fold is what it does to our surface
    o.reason = "the level-set surface folds over itself at " + std::to_string(folds.count) + " triangle" +
               (folds.count == 1 ? "" : "s") + " (" + where + "; a smaller voxel_size resolves it";
  }
  return o;
}

// No excessively thin features. method sdf (default): the shape diameter
// function of Shapira et al. 2008, as Fab Forms Table 2 uses; passes when the
// share of surface area thinner than `value` is at most max_thin_fraction
// (default 0.01). method opening: morphological opening of the level set by a
// ball of diameter `value`; passes when the volume lost is at most
// max_thin_fraction (default 0.02, sharp convex edges always lose a little).
CheckOutcome MinThickness(const CheckSpec& spec, CheckContext& c) {
  double value = c.Number(spec, "value", 1.0);
  auto method_it = spec.args.find("method");
  std::string method = method_it == spec.args.end() ? "sdf" : method_it->second.text;
  CheckOutcome o;
  o.failure = kThinParts;
  std::ostringstream reason;
  if (method == "opening") {
    double allowed = c.Number(spec, "max_thin_fraction", 0.02);
    double lost = geometry::OpeningLossFraction(c.solid(), value);
    o.passed = lost <= allowed;
    reason << 100 * lost << "% of the volume is thinner than " << Mm(value) << " (allowed " << 100 * allowed << "%)";
  } else {
    double allowed = c.Number(spec, "max_thin_fraction", 0.01);
    mesh::ShapeDiameterOptions options;
    options.thin_threshold = value;
    // A fixed-stride sample of 4,000 faces estimates the area fractions to
    // ~0.2% (against every face's, docs/mesh.md); the rays are most of the
    // check's cost.
    options.max_faces = 4000;
    mesh::ShapeDiameterSummary sdf = mesh::ShapeDiameter(c.Mesh(), options);
    o.passed = sdf.area_fraction_below <= allowed;
    reason << 100 * sdf.area_fraction_below << "% of the surface has shape diameter below " << Mm(value)
           << " (thinnest " << Mm(sdf.min) << ", allowed " << 100 * allowed << "%)";
  }
  if (!o.passed)
    o.reason = reason.str();
  else
    o.failure.clear();
  return o;
}

// Stands on a flat surface: the centre of mass projects inside the convex
// support polygon (the lowest points, within a quarter voxel of the minimum
// z), at least `margin` mm from its boundary (Prévost et al. 2013, as cited by
// Fab Forms for its cups).
CheckOutcome Stands(const CheckSpec& spec, CheckContext& c) {
  double margin = c.Number(spec, "margin", 0.0);
  const mesh::TriangleMesh& m = c.Mesh();
  double zmin = std::numeric_limits<double>::infinity();
  for (const auto& v : m.vertices) zmin = std::min(zmin, v[2]);
  double tolerance = 0.25 * c.design().voxel_size;
  std::vector<geometry::Vec2> support;
  for (const auto& v : m.vertices)
    if (v[2] <= zmin + tolerance) support.push_back({v[0], v[1]});
  geometry::Vec3 com = c.solid().CenterOfMass();
  double inside = DistanceInsideConvexHull(support, {com[0], com[1]});
  CheckOutcome o;
  o.passed = inside >= margin;
  if (!o.passed) {
    o.failure = kUnstable;
    std::ostringstream reason;
    if (inside < 0)
      reason << "centre of mass lies " << Mm(-inside) << " outside the support polygon";
    else
      reason << "centre of mass lies only " << Mm(inside) << " inside the support polygon (margin " << Mm(margin)
             << ")";
    o.reason = reason.str();
  }
  return o;
}

CheckOutcome MaxVolume(const CheckSpec& spec, CheckContext& c) {
  double limit = c.Number(spec, "value", 0);
  double volume = c.solid().Volume();
  CheckOutcome o;
  o.passed = volume <= limit;
  if (!o.passed) {
    o.failure = kTooMuchMaterial;
    std::ostringstream reason;
    reason << "material volume " << volume << " mm^3 exceeds " << limit << " mm^3";
    o.reason = reason.str();
  }
  return o;
}

}  // namespace check

double DistanceInsideConvexHull(std::vector<geometry::Vec2> pts, const geometry::Vec2& p) {
  const std::vector<geometry::Vec2> hull = ConvexHull2D(std::move(pts));  // counter-clockwise
  if (hull.size() < 3) return -std::numeric_limits<double>::infinity();
  // Inside: distance to the nearest edge line; outside: distance to the hull.
  bool inside = true;
  double nearest_line = std::numeric_limits<double>::infinity();
  double nearest_segment = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const auto& a = hull[i];
    const auto& b = hull[(i + 1) % hull.size()];
    double ex = b[0] - a[0], ey = b[1] - a[1], len = std::hypot(ex, ey);
    double side = Cross(a, b, p) / len;
    if (side < 0) inside = false;
    nearest_line = std::min(nearest_line, side);
    double t = std::clamp(((p[0] - a[0]) * ex + (p[1] - a[1]) * ey) / (len * len), 0.0, 1.0);
    nearest_segment = std::min(nearest_segment, std::hypot(p[0] - a[0] - t * ex, p[1] - a[1] - t * ey));
  }
  return inside ? nearest_line : -nearest_segment;
}

}  // namespace fabatlas::design
