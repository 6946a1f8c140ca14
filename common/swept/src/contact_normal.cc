// The spacetime contact normal of two moving parts (Reconfigurables, Secs.
// 6.2–6.4). See contact_normal.h.
#include "fabatlas/swept/contact_normal.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

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

Vec3 Add(const Vec3& p, const Vec3& q) { return {p[0] + q[0], p[1] + q[1], p[2] + q[2]}; }
double Dot(const Vec3& p, const Vec3& q) { return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]; }
Vec3 Cross(const Vec3& p, const Vec3& q) {
  return {p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0]};
}

// Where triangle t crosses the plane through `origin` with unit normal n:
// the two extreme points of the crossing (false if t lies on one side or
// in the plane).
bool PlaneCrossing(const std::array<Vec3, 3>& t, const Vec3& origin, const Vec3& n, Vec3& p, Vec3& q) {
  double d[3];
  for (int i = 0; i < 3; ++i) d[i] = Dot(n, Sub(t[i], origin));
  if ((d[0] > 0 && d[1] > 0 && d[2] > 0) || (d[0] < 0 && d[1] < 0 && d[2] < 0)) return false;
  if (d[0] == 0 && d[1] == 0 && d[2] == 0) return false;  // coplanar: no contour direction
  std::vector<Vec3> points;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    if (d[i] == 0) points.push_back(t[i]);
    if ((d[i] < 0 && d[j] > 0) || (d[i] > 0 && d[j] < 0))
      points.push_back(Add(t[i], Scale(Sub(t[j], t[i]), d[i] / (d[i] - d[j]))));
  }
  if (points.size() < 2) return false;  // touching at a vertex
  p = points[0], q = points[1];
  for (std::size_t k = 2; k < points.size(); ++k)
    if (Norm(Sub(points[k], p)) > Norm(Sub(q, p))) q = points[k];
  return true;
}

// The segment where two triangles cross (plain doubles, no constructed
// point reaches an exact predicate): each triangle's crossing of the
// other's plane lies on the planes' common line; the segment is where the
// two overlap along it. False when they do not cross along a segment.
bool CrossingSegment(const std::array<Vec3, 3>& a, const Vec3& na, const std::array<Vec3, 3>& b, const Vec3& nb,
                     Vec3& p, Vec3& q) {
  Vec3 line = Cross(na, nb);
  const double l = Norm(line);
  if (!(l > 1e-12)) return false;  // parallel planes
  line = Scale(line, 1 / l);
  Vec3 a0, a1, b0, b1;
  if (!PlaneCrossing(b, a[0], na, b0, b1) || !PlaneCrossing(a, b[0], nb, a0, a1)) return false;
  double sa0 = Dot(line, a0), sa1 = Dot(line, a1), sb0 = Dot(line, b0), sb1 = Dot(line, b1);
  if (sa0 > sa1) std::swap(sa0, sa1), std::swap(a0, a1);
  if (sb0 > sb1) std::swap(sb0, sb1), std::swap(b0, b1);
  if (std::max(sa0, sb0) >= std::min(sa1, sb1)) return false;
  p = sa0 > sb0 ? a0 : b0;
  q = sa1 < sb1 ? a1 : b1;
  return true;
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

// The samples of the span [t0, t1]: the regular ones (i / (n - 1)) inside,
// and its ends.
std::vector<double> SpanTimes(double t0, double t1, int n) {
  std::vector<double> times{t0};
  for (int i = static_cast<int>(std::ceil(t0 * (n - 1))); i <= static_cast<int>(std::floor(t1 * (n - 1))); ++i) {
    const double t = static_cast<double>(i) / (n - 1);
    if (t > times.back()) times.push_back(t);
  }
  if (t1 > times.back()) times.push_back(t1);
  return times;
}

Vec3 ToVec3(const Point& p) { return {p.x(), p.y(), p.z()}; }

// The contour segments where triangle tb of part b (in a's body frame)
// crosses a's triangles `hits` at time t: one ContourForce each, appended to
// s->forces (world frame by fa, weighted by dt), their lengths (mm) added
// one by one to *length.
void AddContourForces(const Triangle& tb, const std::vector<Tree::Primitive_id>& hits, const Transform& fa, double t,
                      double dt, double* length, ContactNormalSummary* s) {
  const Vec3 nb = UnitNormal({tb[0].x(), tb[0].y(), tb[0].z()}, {tb[1].x(), tb[1].y(), tb[1].z()},
                             {tb[2].x(), tb[2].y(), tb[2].z()});
  const std::array<Vec3, 3> vb{Vec3{tb[0].x(), tb[0].y(), tb[0].z()}, Vec3{tb[1].x(), tb[1].y(), tb[1].z()},
                               Vec3{tb[2].x(), tb[2].y(), tb[2].z()}};
  for (const auto& id : hits) {
    const Triangle& tri_a = *id;
    const std::array<Vec3, 3> va{ToVec3(tri_a[0]), ToVec3(tri_a[1]), ToVec3(tri_a[2])};
    const Vec3 na = UnitNormal(va[0], va[1], va[2]);
    if (Norm(na) == 0 || Norm(nb) == 0) continue;
    Vec3 p, q;
    if (!CrossingSegment(va, na, vb, nb, p, q)) continue;
    const double l = Norm(Sub(q, p));
    const Vec3 bisector = Sub(na, nb);
    const double bl = Norm(bisector);
    if (!(l > 0) || !(bl > 1e-12)) continue;  // equal normals: tangent, no side to leave by
    *length += l;
    // Segments at t0 and t1 are weighted by dt too: the span's ends
    // stand for the sample steps they lie in.
    ContourForce f;
    f.t = t;
    f.point = fa.Apply(Scale(Add(p, q), 0.5));
    f.force = Rotate(fa, Scale(bisector, l * dt / bl));
    f.normal_a = Rotate(fa, na);
    f.normal_b = Rotate(fa, nb);
    s->forces.push_back(f);
  }
}

// The forces' sum (spacetime gradient), its direction (spacetime normal) and
// their Bernstein-weighted sums per cubic control point.
void SumForces(ContactNormalSummary* s) {
  for (const ContourForce& f : s->forces) {
    const double u = f.t, v = 1 - f.t;
    const double bern[4] = {v * v * v, 3 * v * v * u, 3 * v * u * u, u * u * u};
    for (int k = 0; k < 3; ++k) {
      s->spacetime_gradient[k] += f.force[k];
      for (int c = 0; c < 4; ++c) s->control_point_gradient[c][k] += bern[c] * f.force[k];
    }
  }
  const double g = Norm(s->spacetime_gradient);
  if (g > 0) s->spacetime_normal = Scale(s->spacetime_gradient, 1 / g);
}

// Sec. 6.1: the spatial normal at first contact of parts a and b, searched
// from the sample before t0 (the parts are apart there unless they touch
// from the start) to t1.
void FindFirstContact(const std::vector<MovingPart>& parts, int a, int b, double t0, double t1, double dt,
                      const ContactNormalOptions& options, ContactNormalSummary* s) {
  const std::vector<MovingPart> pair{parts[a], parts[b]};
  const ContinuousContact contact(pair);
  double extent = 0;
  for (const auto* m : {&parts[a].mesh, &parts[b].mesh}) {
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
        s->has_first_contact = true;
        s->first_contact_t = c.t;
        s->first_contact_normal = Scale(d, 1 / Norm(d));
      }
    }
  }
}

}  // namespace

ContactNormalSummary SpacetimeContactNormal(const std::vector<MovingPart>& parts, int a, int b, double t0, double t1,
                                            const ContactNormalOptions& options) {
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

  ContactNormalSummary s;
  std::vector<Point> posed(mb.vertices.size());
  std::vector<Tree::Primitive_id> hits;
  for (const double t : SpanTimes(t0, t1, n)) {
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
      AddContourForces(tb, hits, fa, t, dt, &length, &s);
    }
    if (length > 0) ++s.contour_samples;
    s.energy += length * dt;
  }
  SumForces(&s);
  if (options.first_contact) FindFirstContact(parts, a, b, t0, t1, dt, options, &s);
  return s;
}

}  // namespace fabatlas::swept
