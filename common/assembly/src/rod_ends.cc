#include "fabatlas/assembly/rod_ends.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace fabatlas::assembly {
namespace {

struct Triangle {
  Eigen::Vector3d a, b, c;
};

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5).
Eigen::Vector3d ClosestPoint(const Eigen::Vector3d& p, const Triangle& t) {
  const Eigen::Vector3d ab = t.b - t.a, ac = t.c - t.a, ap = p - t.a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return t.a;
  const Eigen::Vector3d bp = p - t.b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return t.b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return t.a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - t.c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return t.c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return t.a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return t.b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (t.c - t.b);
  const double den = 1 / (va + vb + vc);
  return t.a + ab * (vb * den) + ac * (vc * den);
}

// Ray o + s·d (s > 0) against triangle t (Möller–Trumbore): the distance s,
// or infinity; `from_behind` is set when d runs along the winding normal.
double Hit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Triangle& t, bool* from_behind) {
  const Eigen::Vector3d e1 = t.b - t.a, e2 = t.c - t.a, p = d.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-12) return std::numeric_limits<double>::infinity();
  const Eigen::Vector3d s = o - t.a;
  const double u = s.dot(p) / det;
  if (u < 0 || u > 1) return std::numeric_limits<double>::infinity();
  const Eigen::Vector3d q = s.cross(e1);
  const double v = d.dot(q) / det;
  if (v < 0 || u + v > 1) return std::numeric_limits<double>::infinity();
  const double dist = e2.dot(q) / det;
  if (dist <= 0) return std::numeric_limits<double>::infinity();
  *from_behind = det < 0;  // det = −d·(e1×e2): negative when d is along the normal
  return dist;
}

RodEndProbe Probe(const std::vector<Triangle>& all, const Eigen::Vector3d& point, double past_mm,
                  const std::vector<Eigen::Vector3d>& dirs, double max_ray_mm) {
  RodEndProbe r;
  r.past_mm = past_mm;
  r.point = point;
  r.rays = static_cast<int>(dirs.size());
  r.distance_mm = std::numeric_limits<double>::infinity();
  std::vector<const Triangle*> near;
  for (const Triangle& t : all) {
    r.distance_mm = std::min(r.distance_mm, (ClosestPoint(point, t) - point).norm());
    const Eigen::Vector3d lo = t.a.cwiseMin(t.b).cwiseMin(t.c), hi = t.a.cwiseMax(t.b).cwiseMax(t.c);
    if (((lo.array() - max_ray_mm) <= point.array()).all() && ((hi.array() + max_ray_mm) >= point.array()).all())
      near.push_back(&t);
  }
  for (const Eigen::Vector3d& d : dirs) {
    double best = max_ray_mm;
    bool behind = false, hit = false;
    for (const Triangle* t : near) {
      bool b = false;
      const double s = Hit(point, d, *t, &b);
      if (s < best) best = s, behind = b, hit = true;
    }
    if (hit) {
      ++r.rays_hit;
      if (behind) ++r.hits_from_inside;
    }
  }
  return r;
}

}  // namespace

RodEnds MeasureRodEnds(const PartMesh& mesh, const Primitive& rod, const RodEndOptions& options) {
  if (rod.type != PrimitiveType::kRod) throw std::invalid_argument("MeasureRodEnds: '" + rod.name + "' is not a rod");
  std::vector<Triangle> tris;
  tris.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) tris.push_back({mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]});
  std::vector<Eigen::Vector3d> dirs;  // Fibonacci sphere
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < options.rays; ++i) {
    const double z = 1 - (i + 0.5) * 2 / options.rays, r = std::sqrt(1 - z * z);
    dirs.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  const Eigen::Isometry3d base = ToIsometry(rod.frame);
  const Eigen::Vector3d axis = base.linear().col(2);
  const double half = rod.Shape("length") / 2;
  RodEnds out;
  out.t0.position = base * Eigen::Vector3d(0, 0, -half);
  out.t0.outward = -axis;
  out.t1.position = base * Eigen::Vector3d(0, 0, half);
  out.t1.outward = axis;
  for (RodEnd* end : {&out.t0, &out.t1})
    for (double d : options.probe_mm)
      end->probes.push_back(Probe(tris, end->position + d * end->outward, d, dirs, options.max_ray_mm));
  return out;
}

}  // namespace fabatlas::assembly
