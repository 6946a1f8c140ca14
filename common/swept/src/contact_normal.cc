// The spacetime contact normal of two moving parts (Reconfigurables, Secs.
// 6.2–6.4). See contact_normal.h.
#include "fabatlas/swept/contact_normal.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "fabatlas/error.h"
#include "fabatlas/swept/continuous_contact.h"

namespace fabatlas::swept {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Segment = Kernel::Segment_3;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Vec3 Sub(const Vec3& p, const Vec3& q) { return {p[0] - q[0], p[1] - q[1], p[2] - q[2]}; }
Vec3 Scale(const Vec3& p, double s) { return {p[0] * s, p[1] * s, p[2] * s}; }
double Norm(const Vec3& p) { return std::hypot(p[0], p[1], p[2]); }
Vec3 Rotate(const Transform& f, const Vec3& v) {
  Vec3 out{0, 0, 0};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out[r] += f.rotation[r][c] * v[c];
  return out;
}

// Outward unit normal of a counter-clockwise triangle (zero if degenerate).
Vec3 UnitNormal(const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  const Vec3 e1 = Sub(p1, p0), e2 = Sub(p2, p0);
  const Vec3 n{e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
  const double l = Norm(n);
  return l > 0 ? Scale(n, 1 / l) : Vec3{0, 0, 0};
}

void CheckPart(const std::vector<MovingPart>& parts, int p) {
  if (p < 0 || p >= static_cast<int>(parts.size()))
    throw InputError("contact normal: part index " + std::to_string(p) + " out of range");
  const auto& m = parts[p].mesh;
  if (m.triangles.empty()) throw InputError("contact normal: part " + std::to_string(p) + " has no triangles");
  const auto nv = static_cast<std::int64_t>(m.vertices.size());
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || t[k] >= nv)
        throw InputError("contact normal: part " + std::to_string(p) + ": a triangle refers to a missing vertex");
}

}  // namespace

ContactNormalSummary SpacetimeContactNormal(const std::vector<MovingPart>& parts, int a, int b, double t0,
                                            double t1, const ContactNormalOptions& options) {
  CheckPart(parts, a);
  CheckPart(parts, b);
  if (a == b) throw InputError("contact normal: a part against itself");
  if (options.time_steps < 2) throw InputError("contact normal: time_steps must be >= 2");
  if (!(t0 >= 0 && t0 <= t1 && t1 <= 1)) throw InputError("contact normal: the span must satisfy 0 <= t0 <= t1 <= 1");
  const int n = options.time_steps;
  const double dt = 1.0 / (n - 1);

  // Part a in its body frame, once: b's triangles are posed into it.
  const auto& ma = parts[a].mesh;
  const auto& mb = parts[b].mesh;
  std::vector<Triangle> ta;
  ta.reserve(ma.triangles.size());
  for (const auto& t : ma.triangles) {
    const auto& p = ma.vertices[t[0]];
    const auto& q = ma.vertices[t[1]];
    const auto& r = ma.vertices[t[2]];
    ta.emplace_back(Point(p[0], p[1], p[2]), Point(q[0], q[1], q[2]), Point(r[0], r[1], r[2]));
  }
  const Tree tree(ta.cbegin(), ta.cend());
  const CGAL::Bbox_3 box_a = tree.bbox();

  // The samples of the span: the regular ones inside, and its ends.
  std::vector<double> times{t0};
  for (int i = static_cast<int>(std::ceil(t0 * (n - 1))); i <= static_cast<int>(std::floor(t1 * (n - 1))); ++i) {
    const double t = static_cast<double>(i) / (n - 1);
    if (t > times.back()) times.push_back(t);
  }
  if (t1 > times.back()) times.push_back(t1);

  ContactNormalSummary s;
  std::vector<Point> posed(mb.vertices.size());
  std::vector<Tree::Primitive_id> hits;
  for (const double t : times) {
    const Transform fa = parts[a].motion.At(t);
    const Transform into = fa.Inverse().Compose(parts[b].motion.At(t));
    for (std::size_t v = 0; v < posed.size(); ++v) {
      const Vec3 x = into.Apply(mb.vertices[v]);
      posed[v] = Point(x[0], x[1], x[2]);
    }
    double length = 0;
    for (const auto& tri : mb.triangles) {
      const Triangle tb(posed[tri[0]], posed[tri[1]], posed[tri[2]]);
      if (!CGAL::do_overlap(tb.bbox(), box_a) || tb.is_degenerate()) continue;
      hits.clear();
      tree.all_intersected_primitives(tb, std::back_inserter(hits));
      if (hits.empty()) continue;
      const Vec3 nb = UnitNormal({tb[0].x(), tb[0].y(), tb[0].z()}, {tb[1].x(), tb[1].y(), tb[1].z()},
                                 {tb[2].x(), tb[2].y(), tb[2].z()});
      for (const auto& id : hits) {
        const Triangle& tri_a = *id;
        const auto result = CGAL::intersection(tri_a, tb);
        if (!result) continue;
        const Segment* seg = boost::get<Segment>(&*result);
        if (!seg) continue;  // a point (no length) or a coplanar overlap (no contour direction)
        const double l = std::sqrt(CGAL::to_double(seg->squared_length()));
        const Vec3 na = UnitNormal({tri_a[0].x(), tri_a[0].y(), tri_a[0].z()},
                                   {tri_a[1].x(), tri_a[1].y(), tri_a[1].z()},
                                   {tri_a[2].x(), tri_a[2].y(), tri_a[2].z()});
        const Vec3 bisector = Sub(na, nb);
        const double bl = Norm(bisector);
        if (!(l > 0) || !(bl > 1e-12)) continue;  // equal normals: tangent, no side to leave by
        length += l;
        // Segments at t0 and t1 are weighted by dt too: the span's ends
        // stand for the sample steps they lie in.
        ContourForce f;
        f.t = t;
        const Point m = CGAL::midpoint(seg->source(), seg->target());
        f.point = fa.Apply({m.x(), m.y(), m.z()});
        f.force = Rotate(fa, Scale(bisector, l * dt / bl));
        f.normal_a = Rotate(fa, na);
        f.normal_b = Rotate(fa, nb);
        s.forces.push_back(f);
      }
    }
    if (length > 0) ++s.contour_samples;
    s.energy += length * dt;
  }
  for (const ContourForce& f : s.forces) {
    const double u = f.t, v = 1 - f.t;
    const double bern[4] = {v * v * v, 3 * v * v * u, 3 * v * u * u, u * u * u};
    for (int k = 0; k < 3; ++k) {
      s.spacetime_gradient[k] += f.force[k];
      for (int c = 0; c < 4; ++c) s.control_point_gradient[c][k] += bern[c] * f.force[k];
    }
  }
  const double g = Norm(s.spacetime_gradient);
  if (g > 0) s.spacetime_normal = Scale(s.spacetime_gradient, 1 / g);

  // Sec. 6.1: the spatial normal at first contact, searched from the sample
  // before t0 (the parts are apart there unless they touch from the start).
  if (options.first_contact) {
    const std::vector<MovingPart> pair{parts[a], parts[b]};
    const ContinuousContact contact(pair);
    double extent = 0;
    for (const auto* m : {&ma, &mb}) {
      const SpatialBox bb = PosedBox(*m, Transform{});
      for (int k = 0; k < 3; ++k) extent = std::max(extent, bb.max[k] - bb.min[k]);
    }
    ContactSearchOptions co;
    co.tolerance = options.contact_tolerance * std::max(extent, 1e-9);
    const double from = std::max(0.0, t0 - dt);
    if (contact.Distance(0, 1, from) > co.tolerance) {
      const ContactSearch c = contact.Advance(0, 1, from, t1, co);
      if (c.contact) {
        const ContinuousContact::Closest near = contact.Nearest(0, 1, c.t);
        const Vec3 d = Sub(near.point_b, near.point_a);
        if (near.distance > 0 && Norm(d) > 0) {
          s.has_first_contact = true;
          s.first_contact_t = c.t;
          s.first_contact_normal = Scale(d, 1 / Norm(d));
        }
      }
    }
  }
  return s;
}

}  // namespace fabatlas::swept
