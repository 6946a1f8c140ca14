// Spacetime collision intervals (Reconfigurables, section 5): 4D proxy boxes in a
// bounding volume hierarchy, exact confirmation at samples.
#include "fabatlas/swept/spacetime_collision.h"

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>

#include <embree3/rtcore.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <tuple>
#include <map>
#include <memory>
#include <numeric>
#include <set>
#include <string>

#include "fabatlas/error.h"
#include "fabatlas/swept/box_tree.h"
#include "fabatlas/swept/continuous_contact.h"

namespace fabatlas::swept {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Surface = CGAL::Surface_mesh<Point>;
using FaceTree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, CGAL::AABB_face_graph_triangle_primitive<Surface>>>;
using Inside = CGAL::Side_of_triangle_mesh<Surface, Kernel>;

// A part in its body frame, built once: its surface, a tree over its faces
// and a point-in-volume test. Exact tests at every sample pose the other
// part's triangles into this frame instead of rebuilding trees per sample.
struct BodyIndex {
  Surface surface;
  std::unique_ptr<FaceTree> faces;
  std::unique_ptr<Inside> inside;
};

using Box4 = BoxTree<4>::Box;  // [min, max] over (x, y, z, t)

bool Overlap(const Box4& a, const Box4& b) {
  for (int k = 0; k < 4; ++k)
    if (a[0][k] > b[1][k] || b[0][k] > a[1][k]) return false;
  return true;
}

// Proxy pairs (q < r) whose boxes may overlap, from Embree's rtcCollide
// (a BVH over user geometry, built and traversed by Embree). The 4D boxes
// are flattened to 3D: interval i is shifted along x by i * (x range + gap),
// so boxes of different intervals never meet; the float boxes are rounded
// outward, so every overlapping pair is reported (the caller re-checks the
// double boxes).
std::vector<std::pair<int, int>> EmbreeOverlaps(const std::vector<Box4>& boxes, const std::vector<int>& interval) {
  std::vector<std::pair<int, int>> out;
  if (boxes.empty()) return out;
  double lo = 1e300, hi = -1e300;
  for (const Box4& b : boxes) lo = std::min(lo, b[0][0]), hi = std::max(hi, b[1][0]);
  const double slab = (hi - lo) * 1.5 + 1.0;
  struct Data {
    std::vector<RTCBounds> bounds;
    std::mutex mu;
    std::vector<std::pair<int, int>>* out;
  } data;
  data.out = &out;
  data.bounds.resize(boxes.size());
  for (std::size_t q = 0; q < boxes.size(); ++q) {
    const double shift = (interval[q]) * slab - lo;
    RTCBounds& r = data.bounds[q];
    auto down = [](double v) { return std::nextafter(static_cast<float>(v), -INFINITY); };
    auto up = [](double v) { return std::nextafter(static_cast<float>(v), INFINITY); };
    r.lower_x = down(boxes[q][0][0] + shift), r.upper_x = up(boxes[q][1][0] + shift);
    r.lower_y = down(boxes[q][0][1]), r.upper_y = up(boxes[q][1][1]);
    r.lower_z = down(boxes[q][0][2]), r.upper_z = up(boxes[q][1][2]);
  }
  // One device per process (creating one starts Embree's thread pool).
  static const RTCDevice device = rtcNewDevice(nullptr);
  if (!device) throw ResourceError("collision: cannot create an Embree device");
  RTCScene scene = rtcNewScene(device);
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
  rtcSetGeometryUserPrimitiveCount(geometry, static_cast<unsigned>(boxes.size()));
  rtcSetGeometryUserData(geometry, &data);
  rtcSetGeometryBoundsFunction(
      geometry,
      [](const RTCBoundsFunctionArguments* args) {
        *args->bounds_o = static_cast<Data*>(args->geometryUserPtr)->bounds[args->primID];
      },
      nullptr);
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(scene);
  rtcCollide(
      scene, scene,
      [](void* user, RTCCollision* c, unsigned n) {
        auto* d = static_cast<Data*>(user);
        std::lock_guard lock(d->mu);
        for (unsigned k = 0; k < n; ++k)
          if (c[k].primID0 != c[k].primID1)
            d->out->emplace_back(std::min(c[k].primID0, c[k].primID1), std::max(c[k].primID0, c[k].primID1));
      },
      &data);
  rtcReleaseScene(scene);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// Visits every proxy whose box overlaps q, through a BoxTree of the proxies'
// 4D boxes (leaves of up to 4 proxies).
template <typename F>
void VisitOverlaps(const BoxTree<4>& tree, const Box4& q, F&& visit) {
  if (tree.nodes().empty()) return;
  std::vector<int> stack{0};
  while (!stack.empty()) {
    const auto& n = tree.nodes()[stack.back()];
    stack.pop_back();
    if (!Overlap(n.box, q)) continue;
    if (n.count > 0) {
      for (int i = n.first; i < n.first + n.count; ++i) {
        const int item = tree.order()[i];
        if (Overlap(tree.box(item), q)) visit(item);
      }
    } else {
      stack.push_back(n.left);
      stack.push_back(n.right);
    }
  }
}

void CheckPart(const mesh::TriangleMesh& m, std::size_t p) {
  const std::string where = "collision: part " + std::to_string(p);
  if (m.vertices.empty() || m.triangles.empty()) throw InputError(where + ": mesh has no triangles");
  const auto nv = static_cast<std::int64_t>(m.vertices.size());
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || t[k] >= nv) throw InputError(where + ": a triangle refers to a missing vertex");
  for (const auto& v : m.vertices)
    for (double x : v)
      if (!std::isfinite(x)) throw InputError(where + ": non-finite vertex coordinate");
}

Surface Posed(const mesh::TriangleMesh& m, const Transform& f, std::size_t p) {
  Surface s;
  std::vector<Surface::Vertex_index> ids;
  ids.reserve(m.vertices.size());
  for (const auto& v : m.vertices) {
    const Vec3 q = f.Apply(v);
    ids.push_back(s.add_vertex(Point(q[0], q[1], q[2])));
  }
  for (const auto& t : m.triangles) {
    if (s.add_face(ids[t[0]], ids[t[1]], ids[t[2]]) == Surface::null_face()) {
      throw InputError("collision: part " + std::to_string(p) + ": mesh is non-manifold");
    }
  }
  if (!CGAL::is_closed(s)) throw InputError("collision: part " + std::to_string(p) + ": mesh is not closed");
  return s;
}

}  // namespace

SpatialBox PosedBox(const mesh::TriangleMesh& m, const Transform& f) {
  SpatialBox b{{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
  for (const auto& v : m.vertices) {
    const Vec3 q = f.Apply(v);
    for (int k = 0; k < 3; ++k) b.min[k] = std::min(b.min[k], q[k]), b.max[k] = std::max(b.max[k], q[k]);
  }
  return b;
}

namespace {

// The parts' poses and world AABBs at samples i = 0 .. n - 1 (time i / (n -
// 1)), and the largest side of any of those boxes (mm).
struct SampledMotion {
  std::vector<std::vector<Transform>> pose;
  std::vector<std::vector<SpatialBox>> aabb;
  double extent = 0;
};

SampledMotion SampleMotion(const std::vector<MovingPart>& parts, int n) {
  const std::size_t np = parts.size();
  SampledMotion out;
  out.pose.resize(np);
  out.aabb.resize(np);
  for (std::size_t p = 0; p < np; ++p) {
    for (int i = 0; i < n; ++i) {
      const Transform f = parts[p].motion.At(static_cast<double>(i) / (n - 1));
      const SpatialBox b = PosedBox(parts[p].mesh, f);
      for (int k = 0; k < 3; ++k) out.extent = std::max(out.extent, b.max[k] - b.min[k]);
      out.pose[p].push_back(f);
      out.aabb[p].push_back(b);
    }
  }
  return out;
}

// Spacetime proxies: a 4D box per part and interval between samples, time
// scaled by tscale (mm) so the split axis choice treats time like space;
// owner[q]: (part, interval) of boxes[q].
struct Proxies {
  std::vector<Box4> boxes;
  std::vector<std::pair<int, int>> owner;
};

Proxies BuildProxies(const std::vector<std::vector<SpatialBox>>& aabb, int n, double tscale) {
  Proxies out;
  for (std::size_t p = 0; p < aabb.size(); ++p) {
    for (int i = 0; i + 1 < n; ++i) {
      Box4 b;
      for (int k = 0; k < 3; ++k) {
        b[0][k] = std::min(aabb[p][i].min[k], aabb[p][i + 1].min[k]);
        b[1][k] = std::max(aabb[p][i].max[k], aabb[p][i + 1].max[k]);
      }
      b[0][3] = tscale * i / (n - 1);
      b[1][3] = tscale * (i + 1) / (n - 1);
      out.boxes.push_back(b);
      out.owner.emplace_back(static_cast<int>(p), i);
    }
  }
  return out;
}

// Parts that hold one pose throughout: a pair of them is tested once, at
// the first sample, and a collision spans the whole transition.
std::vector<bool> StillParts(const std::vector<std::vector<Transform>>& pose, int n) {
  const std::size_t np = pose.size();
  std::vector<bool> still(np, true);
  for (std::size_t p = 0; p < np; ++p)
    for (int i = 1; i < n && still[p]; ++i)
      still[p] = pose[p][i].rotation == pose[p][0].rotation && pose[p][i].translation == pose[p][0].translation;
  return still;
}

// Candidate (part a, part b, sample), a < b, from overlapping proxies of
// different parts in the same interval, by the broad phase `broad_phase`;
// counts candidate_pairs and broad_phase_seconds into *report.
std::set<std::tuple<int, int, int>> FindCandidates(const Proxies& proxies, const std::vector<bool>& still,
                                                   SpacetimeOptions::BroadPhase broad_phase, CollisionReport* report) {
  const std::vector<Box4>& boxes = proxies.boxes;
  const std::vector<std::pair<int, int>>& owner = proxies.owner;
  std::set<std::tuple<int, int, int>> candidates;  // (a, b, sample)
  auto consider = [&](std::size_t q, std::size_t r) {
    const auto [pa, ia] = owner[q];
    const auto [pb, ib] = owner[r];
    if (pa >= pb || ia != ib) return;  // each pair once; same time interval
    ++report->candidate_pairs;
    if (still[pa] && still[pb]) {
      candidates.emplace(pa, pb, 0);
      return;
    }
    candidates.emplace(pa, pb, ia);
    candidates.emplace(pa, pb, ia + 1);
  };
  const auto broad0 = std::chrono::steady_clock::now();
  if (broad_phase == SpacetimeOptions::BroadPhase::kHierarchy) {
    const BoxTree<4> tree(boxes);
    for (std::size_t q = 0; q < boxes.size(); ++q) VisitOverlaps(tree, boxes[q], [&](int r) { consider(q, r); });
  } else if (broad_phase == SpacetimeOptions::BroadPhase::kEmbree) {
    std::vector<int> interval;
    for (const auto& o : owner) interval.push_back(o.second);
    for (const auto& [q, r] : EmbreeOverlaps(boxes, interval)) {
      if (!Overlap(boxes[q], boxes[r])) continue;  // float rounding only widened the boxes
      consider(q, r);
      consider(r, q);
    }
  } else {
    for (std::size_t q = 0; q < boxes.size(); ++q)
      for (std::size_t r = 0; r < boxes.size(); ++r)
        if (Overlap(boxes[q], boxes[r])) consider(q, r);
  }
  report->broad_phase_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - broad0).count();
  return candidates;
}

// The parts in their body frames, each built on first use.
class BodyIndexes {
 public:
  explicit BodyIndexes(const std::vector<MovingPart>& parts) : parts_(parts) {}
  const BodyIndex& Of(int p) {
    auto it = index_.find(p);
    if (it != index_.end()) return it->second;
    BodyIndex& b = index_[p];
    b.surface = Posed(parts_[p].mesh, Transform{}, p);
    b.faces = std::make_unique<FaceTree>(faces(b.surface).first, faces(b.surface).second, b.surface);
    b.inside = std::make_unique<Inside>(b.surface);
    return b;
  }

 private:
  const std::vector<MovingPart>& parts_;
  std::map<int, BodyIndex> index_;
};

// Whether parts a and b collide at sample i: surfaces touching or crossing,
// or one part inside the other (the bounded-side semantics of
// PMP::do_intersect). Both parts in their body frames; the smaller part's
// triangles posed into the larger part's frame by f_large^-1 f_small.
bool CollideAt(const std::vector<MovingPart>& parts, const std::vector<std::vector<Transform>>& pose,
               BodyIndexes* index, int a, int b, int i) {
  const BodyIndex& ia = index->Of(a);
  const BodyIndex& ib = index->Of(b);
  // Pose the smaller part's triangles into the larger part's frame.
  const bool a_small = parts[a].mesh.triangles.size() <= parts[b].mesh.triangles.size();
  const int small = a_small ? a : b, large = a_small ? b : a;
  const BodyIndex& il = a_small ? ib : ia;
  const Transform into = pose[large][i].Inverse().Compose(pose[small][i]);
  const auto& m = parts[small].mesh;
  std::vector<Point> q(m.vertices.size());
  for (std::size_t v = 0; v < q.size(); ++v) {
    const Vec3 x = into.Apply(m.vertices[v]);
    q[v] = Point(x[0], x[1], x[2]);
  }
  const CGAL::Bbox_3 box = il.faces->bbox();
  for (const auto& t : m.triangles) {
    const Kernel::Triangle_3 tri(q[t[0]], q[t[1]], q[t[2]]);
    if (!CGAL::do_overlap(tri.bbox(), box)) continue;
    if (tri.is_degenerate()) continue;
    if (il.faces->do_intersect(tri)) return true;
  }
  // No surface contact: one contains the other, or they are apart.
  if ((*il.inside)(q[0]) != CGAL::ON_UNBOUNDED_SIDE) return true;
  const BodyIndex& is = a_small ? ia : ib;
  const Vec3 y = into.Inverse().Apply(parts[large].mesh.vertices[0]);
  return (*is.inside)(Point(y[0], y[1], y[2])) != CGAL::ON_UNBOUNDED_SIDE;
}

using SampleHits = std::map<std::pair<int, int>, std::vector<int>>;  // pair -> colliding samples, ascending

// The exact test at the candidate samples whose world AABBs meet (counted in
// report->exact_tests); a pair of still parts that collides does so at every
// sample.
SampleHits TestCandidates(const std::vector<MovingPart>& parts, const SampledMotion& motion,
                          const std::vector<bool>& still, const std::set<std::tuple<int, int, int>>& candidates, int n,
                          CollisionReport* report) {
  BodyIndexes index(parts);
  SampleHits hits;
  for (const auto& [a, b, i] : candidates) {
    const SpatialBox& ba = motion.aabb[a][i];
    const SpatialBox& bb = motion.aabb[b][i];
    bool apart = false;
    for (int k = 0; k < 3; ++k) apart |= ba.min[k] > bb.max[k] || bb.min[k] > ba.max[k];
    if (apart) continue;
    ++report->exact_tests;
    // A part wholly inside another collides too.
    if (CollideAt(parts, motion.pose, &index, a, b, i)) {
      if (still[a] && still[b]) {
        for (int j = 0; j < n; ++j) hits[{a, b}].push_back(j);
      } else {
        hits[{a, b}].push_back(i);
      }
    }
  }
  return hits;
}

// The box where parts a and b may meet over [t_begin, t_end]: the union,
// over both times, of the intersection of their posed world AABBs.
SpatialBox ContactBox(const std::vector<MovingPart>& parts, std::size_t a, std::size_t b, double t_begin,
                      double t_end) {
  SpatialBox where = {{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
  for (double t : {t_begin, t_end}) {
    SpatialBox box[2];
    for (int q = 0; q < 2; ++q) {
      const std::size_t p = q ? b : a;
      const Transform f = parts[p].motion.At(t);
      box[q] = {{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
      for (const auto& v : parts[p].mesh.vertices) {
        const Vec3 x = f.Apply(v);
        for (int k = 0; k < 3; ++k)
          box[q].min[k] = std::min(box[q].min[k], x[k]), box[q].max[k] = std::max(box[q].max[k], x[k]);
      }
    }
    for (int k = 0; k < 3; ++k) {
      where.min[k] = std::min(where.min[k], std::max(box[0].min[k], box[1].min[k]));
      where.max[k] = std::max(where.max[k], std::min(box[0].max[k], box[1].max[k]));
    }
  }
  return where;
}

// Between samples: (pair, step) whose boxes, grown by each part's travel
// bound over one step, meet while neither end sample collides; the contact
// found by conservative advancement is appended to report->intervals.
void SearchBetweenSamples(const std::vector<MovingPart>& parts, const SampledMotion& motion,
                          const std::vector<bool>& still, const SampleHits& hits, const SpacetimeOptions& options,
                          double tscale, CollisionReport* report) {
  const int n = options.time_steps;
  const std::size_t np = parts.size();
  const std::vector<std::vector<SpatialBox>>& aabb = motion.aabb;
  const ContinuousContact contact(parts);
  ContactSearchOptions co;
  co.tolerance = options.contact_tolerance * tscale;
  const double dt = 1.0 / (n - 1);
  auto grown = [&](std::size_t p, int i) {
    const double r = contact.SpeedBound(static_cast<int>(p)) * dt;
    SpatialBox b;
    for (int k = 0; k < 3; ++k) {
      // Each end sample's box grown by the travel bound contains the part
      // throughout the step; so does their intersection.
      b.min[k] = std::max(aabb[p][i].min[k], aabb[p][i + 1].min[k]) - r;
      b.max[k] = std::min(aabb[p][i].max[k], aabb[p][i + 1].max[k]) + r;
    }
    return b;
  };
  for (std::size_t a = 0; a < np; ++a)
    for (std::size_t b = a + 1; b < np; ++b) {
      if (still[a] && still[b]) continue;
      const auto hit_it = hits.find({static_cast<int>(a), static_cast<int>(b)});
      auto collides_at = [&](int i) {
        return hit_it != hits.end() && std::binary_search(hit_it->second.begin(), hit_it->second.end(), i);
      };
      for (int i = 0; i + 1 < n; ++i) {
        if (collides_at(i) || collides_at(i + 1)) continue;  // the sampled interval covers this step
        const SpatialBox ga = grown(a, i), gb = grown(b, i);
        bool apart = false;
        for (int k = 0; k < 3; ++k) apart |= ga.min[k] > gb.max[k] || gb.min[k] > ga.max[k];
        if (apart) continue;
        ++report->continuous_searches;
        const double t0 = i * dt, t1 = (i + 1) * dt;
        const ContactSearch first = contact.Advance(static_cast<int>(a), static_cast<int>(b), t0, t1, co);
        report->distance_queries += first.steps;
        if (!first.contact) continue;
        const ContactSearch last = contact.Advance(static_cast<int>(a), static_cast<int>(b), t1, first.t, co);
        report->distance_queries += last.steps;
        CollisionInterval c;
        c.part_a = static_cast<int>(a);
        c.part_b = static_cast<int>(b);
        c.t_begin = first.t;
        c.t_end = last.contact ? last.t : first.t;
        c.where = ContactBox(parts, a, b, c.t_begin, c.t_end);
        report->intervals.push_back(c);
      }
    }
}

// Runs of consecutive colliding samples -> intervals (when), with their box
// (where), appended to *intervals.
void AppendSampledIntervals(const SampleHits& hits, const std::vector<std::vector<SpatialBox>>& aabb, int n,
                            std::vector<CollisionInterval>* intervals) {
  for (const auto& [pair, samples] : hits) {
    std::size_t s = 0;
    while (s < samples.size()) {
      std::size_t e = s;
      while (e + 1 < samples.size() && samples[e + 1] == samples[e] + 1) ++e;
      CollisionInterval c;
      c.part_a = pair.first;
      c.part_b = pair.second;
      c.t_begin = static_cast<double>(samples[s]) / (n - 1);
      c.t_end = static_cast<double>(samples[e]) / (n - 1);
      c.where = {{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
      for (std::size_t j = s; j <= e; ++j) {
        const SpatialBox& ba = aabb[pair.first][samples[j]];
        const SpatialBox& bb = aabb[pair.second][samples[j]];
        for (int k = 0; k < 3; ++k) {
          c.where.min[k] = std::min(c.where.min[k], std::max(ba.min[k], bb.min[k]));
          c.where.max[k] = std::max(c.where.max[k], std::min(ba.max[k], bb.max[k]));
        }
      }
      intervals->push_back(c);
      s = e + 1;
    }
  }
}

}  // namespace

CollisionReport DetectCollisions(const std::vector<MovingPart>& parts, const SpacetimeOptions& options) {
  if (options.time_steps < 2) throw InputError("collision: time_steps must be >= 2");
  const int n = options.time_steps;
  const std::size_t np = parts.size();
  for (std::size_t p = 0; p < np; ++p) CheckPart(parts[p].mesh, p);

  // Poses and world AABBs at every sample.
  const SampledMotion motion = SampleMotion(parts, n);
  // Spacetime proxies, time scaled to the spatial extent so the split axis
  // choice treats time like space.
  const double tscale = std::max(motion.extent, 1e-9);
  const Proxies proxies = BuildProxies(motion.aabb, n, tscale);
  CollisionReport report;
  report.proxies = proxies.boxes.size();

  const std::vector<bool> still = StillParts(motion.pose, n);
  const std::set<std::tuple<int, int, int>> candidates = FindCandidates(proxies, still, options.broad_phase, &report);
  // Exact test at candidate samples.
  const SampleHits hits = TestCandidates(parts, motion, still, candidates, n, &report);
  if (options.continuous && np > 1) SearchBetweenSamples(parts, motion, still, hits, options, tscale, &report);
  AppendSampledIntervals(hits, motion.aabb, n, &report.intervals);
  std::sort(report.intervals.begin(), report.intervals.end(), [](const auto& x, const auto& y) {
    return std::tie(x.t_begin, x.part_a, x.part_b) < std::tie(y.t_begin, y.part_a, y.part_b);
  });
  return report;
}

}  // namespace fabatlas::swept
