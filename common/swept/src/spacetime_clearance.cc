// Minimum clearance between moving parts (see spacetime_clearance.h).
#include "fabatlas/swept/spacetime_clearance.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <string>
#include <tuple>

#include "fabatlas/error.h"

namespace fabatlas::swept {
namespace {

using K = CGAL::Simple_cartesian<double>;
using Triangle = K::Triangle_3;
using Triangles = std::vector<Triangle>;
using Primitive = CGAL::AABB_triangle_primitive<K, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

// One part in its body frame: triangles, their tree, the body box.
struct Body {
  Triangles triangles;
  std::unique_ptr<Tree> tree;
  SpatialBox box;
};

double BoxDistance(const SpatialBox& a, const SpatialBox& b) {
  double s = 0;
  for (int k = 0; k < 3; ++k) {
    const double gap = std::max({0.0, a.min[k] - b.max[k], b.min[k] - a.max[k]});
    s += gap * gap;
  }
  return std::sqrt(s);
}

double PointBoxDistance(const Vec3& p, const SpatialBox& b) {
  double s = 0;
  for (int k = 0; k < 3; ++k) {
    const double gap = std::max({0.0, b.min[k] - p[k], p[k] - b.max[k]});
    s += gap * gap;
  }
  return std::sqrt(s);
}

// Part p's body, built in place (the tree holds iterators into the
// triangles): its non-degenerate triangles in its body frame, their tree
// (accelerated for distance queries) and its box. Throws InputError naming
// the part for an empty or bad mesh.
void BuildBody(const mesh::TriangleMesh& m, std::size_t p, Body& body) {
  const std::string where = "clearance: part " + std::to_string(p);
  if (m.vertices.empty() || m.triangles.empty()) throw InputError(where + ": mesh has no triangles");
  const auto nv = static_cast<std::int64_t>(m.vertices.size());
  for (const auto& t : m.triangles) {
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || t[k] >= nv) throw InputError(where + ": a triangle refers to a missing vertex");
    const auto &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
    Triangle tri(K::Point_3(a[0], a[1], a[2]), K::Point_3(b[0], b[1], b[2]), K::Point_3(c[0], c[1], c[2]));
    if (!tri.is_degenerate()) body.triangles.push_back(tri);
  }
  for (const auto& v : m.vertices)
    for (double x : v)
      if (!std::isfinite(x)) throw InputError(where + ": non-finite vertex coordinate");
  if (body.triangles.empty()) throw InputError(where + ": every triangle is degenerate");
  body.tree = std::make_unique<Tree>(body.triangles.begin(), body.triangles.end());
  body.tree->accelerate_distance_queries();
  body.box = PosedBox(m, Transform{});
}

// A (pair, sample) work item and the distance of the pair's world boxes at
// that sample (mm), a lower bound of its clearance.
struct Item {
  double lower_bound;
  int a, b, i;
};

// The (pair, sample) work items, nearest bounding boxes first so that the
// best distance shrinks early and prunes the rest. A pair of parts that both
// hold one pose is measured at the first sample.
std::vector<Item> WorkItems(const std::vector<std::vector<Transform>>& pose,
                            const std::vector<std::vector<SpatialBox>>& box, int n) {
  const std::size_t np = pose.size();
  std::vector<bool> still(np, true);
  for (std::size_t p = 0; p < np; ++p)
    for (int i = 1; i < n && still[p]; ++i)
      still[p] = pose[p][i].rotation == pose[p][0].rotation && pose[p][i].translation == pose[p][0].translation;
  std::vector<Item> items;
  for (std::size_t a = 0; a < np; ++a)
    for (std::size_t b = a + 1; b < np; ++b)
      for (int i = 0; i < ((still[a] && still[b]) ? 1 : n); ++i)
        items.push_back({BoxDistance(box[a][i], box[b][i]), static_cast<int>(a), static_cast<int>(b), i});
  std::sort(items.begin(), items.end(), [](const Item& x, const Item& y) {
    return std::tie(x.lower_bound, x.i, x.a, x.b) < std::tie(y.lower_bound, y.i, y.a, y.b);
  });
  return items;
}

// The closest vertex of `from` found by Nearest: (distance, vertex in
// `from`'s body frame, closest point in `to`'s body frame).
struct Near {
  double distance;
  Vec3 from_point, to_point;
  std::size_t queries;
  bool found;  // a vertex came at least as close as the best on entry
};

// Closest vertex of `from` (posed into `to`'s body frame by into_to) to the
// triangles of `to`, given the current best (mm); vertices whose distance to
// `to`'s box exceeds the best so far are skipped.
Near Nearest(const mesh::TriangleMesh& from, const Transform& into_to, const Body& to, double best) {
  Near out{best, {0, 0, 0}, {0, 0, 0}, 0, false};
  for (const auto& v : from.vertices) {
    const Vec3 q = into_to.Apply(v);
    if (PointBoxDistance(q, to.box) > out.distance) continue;
    ++out.queries;
    const K::Point_3 c = to.tree->closest_point(K::Point_3(q[0], q[1], q[2]));
    const double d = std::sqrt(CGAL::squared_distance(c, K::Point_3(q[0], q[1], q[2])));
    if (d < out.distance || (d == out.distance && !out.found)) out = {d, v, {c.x(), c.y(), c.z()}, out.queries, true};
  }
  return out;
}

}  // namespace

ClearanceReport MinimumClearance(const std::vector<MovingPart>& parts, const ClearanceOptions& options) {
  if (options.time_steps < 2) throw InputError("clearance: time_steps must be >= 2");
  const int n = options.time_steps;
  const std::size_t np = parts.size();
  std::vector<Body> bodies(np);
  for (std::size_t p = 0; p < np; ++p) BuildBody(parts[p].mesh, p, bodies[p]);

  // Poses and world boxes at every sample.
  std::vector<std::vector<Transform>> pose(np);
  std::vector<std::vector<SpatialBox>> box(np);
  for (std::size_t p = 0; p < np; ++p)
    for (int i = 0; i < n; ++i) {
      pose[p].push_back(parts[p].motion.At(static_cast<double>(i) / (n - 1)));
      box[p].push_back(PosedBox(parts[p].mesh, pose[p].back()));
    }
  const std::vector<Item> items = WorkItems(pose, box, n);

  ClearanceReport report;
  report.min_clearance = options.max_distance;
  std::mutex mutex;
  int best_i = -1;  // sample of the reported pair
  tbb::parallel_for(std::size_t{0}, items.size(), [&](std::size_t k) {
    const Item& it = items[k];
    double best;
    {
      std::lock_guard lock(mutex);
      best = report.min_clearance;
      if (it.lower_bound > best) return;
      ++report.pair_samples_tested;
    }
    const Transform& fa = pose[it.a][it.i];
    const Transform& fb = pose[it.b][it.i];
    const Near ab = Nearest(parts[it.a].mesh, fb.Inverse().Compose(fa), bodies[it.b], best);
    const Near ba = Nearest(parts[it.b].mesh, fa.Inverse().Compose(fb), bodies[it.a], std::min(best, ab.distance));
    std::lock_guard lock(mutex);
    report.vertex_queries += ab.queries + ba.queries;
    const bool from_b = ba.found && (!ab.found || ba.distance < ab.distance);
    const Near& near = from_b ? ba : ab;
    if (!near.found) return;
    // Ties between items at equal distance resolve to the earliest sample
    // (then the lowest pair), so the report does not depend on scheduling.
    if (near.distance > report.min_clearance) return;
    if (near.distance == report.min_clearance && report.part_a >= 0 &&
        std::tie(it.i, it.a, it.b) >= std::tie(best_i, report.part_a, report.part_b))
      return;
    const double t = static_cast<double>(it.i) / (n - 1);
    best_i = it.i;
    report.min_clearance = near.distance;
    report.t = t;
    report.part_a = it.a;
    report.part_b = it.b;
    report.point_a = from_b ? fa.Apply(near.to_point) : fa.Apply(near.from_point);
    report.point_b = from_b ? fb.Apply(near.from_point) : fb.Apply(near.to_point);
  });
  if (np >= 2 && report.part_a < 0) {
    // Nothing closer than max_distance.
    report.part_a = 0;
    report.part_b = 1;
  }
  return report;
}

}  // namespace fabatlas::swept
