// The leaves of OpenSCAD's CSG tree on the level-set road (csg_evaluation.h):
// primitives as exact distance fields where convex, straight extrusions as
// prism fields, everything else sampled from its mesh.
#include "csg_evaluation.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>

#include "fabatlas/error.h"
#include "fabatlas/geometry/convex_mesh_distance.h"
#include "fabatlas/mesh/exact_boolean.h"
#include "fabatlas/scad/primitive_mesh.h"
#include "fabatlas/scad/region_outline.h"
#include "fabatlas/sha256.h"

namespace fabatlas::design::csg {

namespace fs = std::filesystem;

Solid CsgEvaluation::FromMesh(mesh::TriangleMesh m, const Affine& a) {
  if (m.triangles.empty()) return Solid();
  Transform(m, a);
  return geometry::FromMesh(c_.grid, m);
}

CsgEvaluation::Result CsgEvaluation::Convex(mesh::TriangleMesh m, const Affine& a) {
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

Solid CsgEvaluation::Extruded(const Shape2& s, const std::function<mesh::TriangleMesh(const Loop&)>& build,
                              const Affine& m) {
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

void CsgEvaluation::HullPoints(const CsgNode& n, const Affine& m, std::vector<std::array<double, 3>>& out) {
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

mesh::TriangleMesh CsgEvaluation::PrimitiveMesh(const CsgNode& n) {
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

CsgEvaluation::Result CsgEvaluation::Leaf(const CsgNode& n, const Affine& m) {
  if (n.name == "cube" || n.name == "sphere" || n.name == "cylinder") return Convex(PrimitiveMesh(n), m);
  if (n.name == "polyhedron") {
    mesh::TriangleMesh mm = PrimitiveMesh(n);
    Outside(model_.filename().string() + ": polyhedron (CSG line " + std::to_string(n.line) + ")",
            Sha256Hex(n.canonical), mm);
    return {FromMesh(std::move(mm), m), nullptr, ""};
  }
  if (n.name == "linear_extrude") return LinearExtruded(n, m);
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
  if (n.name == "import") return Imported(n, m);
  throw NoNativeEquivalent{n.name};
}

CsgEvaluation::Result CsgEvaluation::LinearExtruded(const CsgNode& n, const Affine& m) {
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

CsgEvaluation::Result CsgEvaluation::Imported(const CsgNode& n, const Affine& m) {
  const std::optional<fs::path> file = ImportedMeshFile(n);
  if (!file) throw NoNativeEquivalent{"import of a 2D file among 3D objects"};
  mesh::TriangleMesh mm;
  try {
    mm = ReadImportedMesh(n, *file);
  } catch (const InputError& e) {
    throw SampleFailure(kNoGeometry, e.what());
  }
  return {FromMesh(std::move(mm), m), nullptr, ""};
}

std::optional<CsgEvaluation::Result> CsgEvaluation::Prism(const Shape2& s, double h, bool center, const Affine& m) {
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

}  // namespace fabatlas::design::csg
