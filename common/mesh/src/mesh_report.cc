// Mesh checks: topology (border / non-manifold / orientation) from a sorted
// edge list over merged vertices, measures by the divergence theorem, and
// self-intersection with CGAL Polygon_mesh_processing.
#include "fabatlas/mesh/mesh_report.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <string>
#include <utility>

#include "fabatlas/mesh/enclosed_volume.h"
#include "fabatlas/mesh/surface_area.h"
#include <vector>

namespace fabatlas::mesh {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
namespace PMP = CGAL::Polygon_mesh_processing;

class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) { Reset(n); }
  // n singletons again, reusing the storage.
  void Reset(std::size_t n) {
    parent_.resize(n);
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  std::size_t Find(std::size_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void Join(std::size_t a, std::size_t b) {
    a = Find(a);
    b = Find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<std::size_t> parent_;
};

// Output iterator that counts intersecting pairs and stops CGAL at the cap.
struct PairLimitReached {};
struct PairCounter {
  std::int64_t* count;
  std::int64_t cap;
  PairCounter& operator*() { return *this; }
  PairCounter& operator++() { return *this; }
  PairCounter operator++(int) { return *this; }
  template <typename Pair>
  PairCounter& operator=(const Pair&) {
    if (++*count >= cap) throw PairLimitReached{};
    return *this;
  }
};

std::string Plural(std::int64_t n, const std::string& one, const std::string& many = "") {
  return std::to_string(n) + " " + (n == 1 ? one : many.empty() ? one + "s" : many);
}

// The mesh's vertices with bit-identical coordinates merged: the distinct
// points in lexicographic order, and for each input vertex its point.
struct MergedVertices {
  std::vector<std::array<double, 3>> points;
  std::vector<std::int32_t> merged;
};

MergedVertices MergeVertices(const TriangleMesh& mesh) {
  const std::size_t nv_in = mesh.vertices.size();
  MergedVertices out;
  out.merged.resize(nv_in);
  std::vector<std::int32_t> order(nv_in);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
    return mesh.vertices[a] < mesh.vertices[b] || (mesh.vertices[a] == mesh.vertices[b] && a < b);
  });
  out.points.reserve(nv_in);
  for (std::size_t k = 0; k < nv_in; ++k) {
    if (k == 0 || mesh.vertices[order[k]] != mesh.vertices[order[k - 1]]) out.points.push_back(mesh.vertices[order[k]]);
    out.merged[order[k]] = static_cast<std::int32_t>(out.points.size() - 1);
  }
  return out;
}

// The triangles over merged vertices, without those with a repeated corner
// (counted in report->degenerate_triangles), and whether each kept one is
// collinear (also counted there).
struct MergedTriangles {
  std::vector<std::array<std::int32_t, 3>> tris;
  std::vector<char> collinear;
};

MergedTriangles MergeTriangles(const TriangleMesh& mesh, const MergedVertices& vertices, MeshReport* report) {
  const std::int64_t nv_signed = static_cast<std::int64_t>(mesh.vertices.size());
  const std::vector<std::int32_t>& merged = vertices.merged;
  const std::vector<std::array<double, 3>>& points = vertices.points;
  MergedTriangles out;
  out.tris.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    bool in_range = true;
    for (std::int32_t v : t) in_range = in_range && v >= 0 && v < nv_signed;
    if (!in_range) continue;  // ReadMesh never produces these; ignore defensively
    const std::array<std::int32_t, 3> m{merged[t[0]], merged[t[1]], merged[t[2]]};
    if (m[0] == m[1] || m[1] == m[2] || m[0] == m[2]) {
      ++report->degenerate_triangles;
      continue;
    }
    const auto& a = points[m[0]];
    const auto& b = points[m[1]];
    const auto& c = points[m[2]];
    const bool flat = CGAL::collinear(Point(a[0], a[1], a[2]), Point(b[0], b[1], b[2]), Point(c[0], c[1], c[2]));
    if (flat) ++report->degenerate_triangles;
    out.tris.push_back(m);
    out.collinear.push_back(flat ? 1 : 0);
  }
  return out;
}

// Measures into *report: bbox of used vertices (mm), area (mm^2), signed
// volume (mm^3) about the bbox centre.
void Measure(const std::vector<std::array<double, 3>>& points, const std::vector<std::array<std::int32_t, 3>>& tris,
             MeshReport* report) {
  if (!tris.empty()) {
    report->bbox_min = {INFINITY, INFINITY, INFINITY};
    report->bbox_max = {-INFINITY, -INFINITY, -INFINITY};
    for (const auto& t : tris) {
      for (std::int32_t v : t) {
        for (int a = 0; a < 3; ++a) {
          report->bbox_min[a] = std::min(report->bbox_min[a], points[v][a]);
          report->bbox_max[a] = std::max(report->bbox_max[a], points[v][a]);
        }
      }
    }
  }
  std::array<double, 3> centre;
  for (int a = 0; a < 3; ++a) centre[a] = 0.5 * (report->bbox_min[a] + report->bbox_max[a]);
  const TriangleMesh used{points, tris};
  report->volume = EnclosedVolume(used, centre);
  report->area = SurfaceArea(used, centre);
}

// A triangle side listed under its lower vertex lo.
struct HalfEdge {
  std::int32_t hi;
  bool forward;  // traversed lo -> hi
  bool operator<(const HalfEdge& o) const { return hi < o.hi; }
};

// Per vertex: the triangle sides under their lower vertex (edges[first[v] ..
// first[v + 1]), unsorted) and the triangles around it (incident[start[v] ..
// start[v + 1])).
struct VertexStars {
  std::vector<std::int32_t> first;
  std::vector<HalfEdge> edges;
  std::vector<std::int32_t> start;
  std::vector<std::int32_t> incident;
};

VertexStars ListStars(std::size_t n_points, const std::vector<std::array<std::int32_t, 3>>& tris) {
  VertexStars stars;
  std::vector<std::int32_t>& first = stars.first;
  first.assign(n_points + 1, 0);
  for (const auto& t : tris)
    for (int k = 0; k < 3; ++k) ++first[std::min(t[k], t[(k + 1) % 3]) + 1];
  std::partial_sum(first.begin(), first.end(), first.begin());
  stars.edges.resize(first.back());
  {
    std::vector<std::int32_t> fill(first.begin(), first.end() - 1);
    for (const auto& t : tris) {
      for (int k = 0; k < 3; ++k) {
        const std::int32_t a = t[k], b = t[(k + 1) % 3];
        stars.edges[fill[std::min(a, b)]++] = {std::max(a, b), a < b};
      }
    }
  }
  std::vector<std::int32_t>& start = stars.start;
  start.assign(n_points + 1, 0);
  for (const auto& t : tris)
    for (std::int32_t v : t) ++start[v + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  stars.incident.resize(start.back());
  {
    std::vector<std::int32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t f = 0; f < tris.size(); ++f)
      for (std::int32_t v : tris[f]) stars.incident[fill[v]++] = static_cast<std::int32_t>(f);
  }
  return stars;
}

struct Counts {
  std::int64_t border = 0, non_manifold_edges = 0, inconsistent = 0, non_manifold_vertices = 0;
};

// Sorts vertex v's edges (so equal edges are adjacent) and counts them into
// *c: border (one face), non-manifold (3+ faces), inconsistent (two faces
// traversing it the same way).
void CountEdges(VertexStars* stars, std::size_t v, Counts* c) {
  const auto begin = stars->edges.begin() + stars->first[v], end = stars->edges.begin() + stars->first[v + 1];
  std::sort(begin, end);
  for (auto i = begin; i != end;) {
    auto j = i;
    int forward = 0;
    while (j != end && j->hi == i->hi) forward += (j++)->forward;
    const auto n = j - i;
    if (n == 1)
      ++c->border;
    else if (n > 2)
      ++c->non_manifold_edges;
    else if (forward != 1)
      ++c->inconsistent;
    i = j;
  }
}

constexpr std::int32_t kSmallFan = 16;

// Whether the deg <= kSmallFan faces around vertex v form more than one fan:
// faces joined pairwise when they share a corner other than v, on the stack.
bool SmallStarIsSplit(const VertexStars& stars, const std::vector<std::array<std::int32_t, 3>>& tris, std::size_t v,
                      std::int32_t deg) {
  const std::vector<std::int32_t>& start = stars.start;
  std::array<std::int32_t, 2 * kSmallFan> other;
  std::array<std::int8_t, kSmallFan> fan;
  for (std::int32_t k = 0; k < deg; ++k) {
    const auto& t = tris[stars.incident[start[v] + k]];
    const int at = t[0] == static_cast<std::int32_t>(v) ? 0 : t[1] == static_cast<std::int32_t>(v) ? 1 : 2;
    other[2 * k] = t[(at + 1) % 3];
    other[2 * k + 1] = t[(at + 2) % 3];
    fan[k] = static_cast<std::int8_t>(k);
  }
  auto find = [&fan](int x) {
    while (fan[x] != x) x = fan[x] = fan[fan[x]];
    return x;
  };
  for (std::int32_t i = 0; i < deg; ++i)
    for (std::int32_t j = i + 1; j < deg; ++j)
      if (other[2 * i] == other[2 * j] || other[2 * i] == other[2 * j + 1] || other[2 * i + 1] == other[2 * j] ||
          other[2 * i + 1] == other[2 * j + 1]) {
        const int a = find(i), b = find(j);
        if (a != b) fan[std::max(a, b)] = static_cast<std::int8_t>(std::min(a, b));
      }
  std::int32_t roots = 0;
  for (std::int32_t k = 0; k < deg; ++k) roots += find(k) == k;
  return roots > 1;
}

// The same for any degree, by sorting the (other corner, face) pairs;
// `around` and `fans` are scratch.
bool LargeStarIsSplit(const VertexStars& stars, const std::vector<std::array<std::int32_t, 3>>& tris, std::size_t v,
                      std::int32_t deg, std::vector<std::pair<std::int32_t, std::int32_t>>* around,
                      DisjointSets* fans) {
  around->clear();
  for (std::int32_t k = 0; k < deg; ++k) {
    const auto& t = tris[stars.incident[stars.start[v] + k]];
    for (std::int32_t w : t)
      if (w != static_cast<std::int32_t>(v)) around->push_back({w, k});
  }
  std::sort(around->begin(), around->end());
  fans->Reset(static_cast<std::size_t>(deg));
  for (std::size_t i = 1; i < around->size(); ++i)
    if ((*around)[i].first == (*around)[i - 1].first) fans->Join((*around)[i].second, (*around)[i - 1].second);
  std::int32_t roots = 0;
  for (std::int32_t k = 0; k < deg; ++k) roots += fans->Find(k) == static_cast<std::size_t>(k);
  return roots > 1;
}

// 4. Edges: the triangle sides (hi, forward?) listed under their lower
//    vertex lo (a bucket per vertex, then each short bucket sorted), so
//    equal edges are adjacent.
// 5. Vertex manifoldness: the faces around a vertex must form one fan
//    (connected through edges incident to that vertex).
//    Both per vertex, over vertex ranges in parallel (TBB); the counts are
//    sums, the same whatever the schedule.
Counts CountTopology(std::size_t n_points, const std::vector<std::array<std::int32_t, 3>>& tris) {
  VertexStars stars = ListStars(n_points, tris);
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n_points, 1024), Counts{},
      [&](const tbb::blocked_range<std::size_t>& range, Counts c) {
        std::vector<std::pair<std::int32_t, std::int32_t>> around;  // (other vertex, local face)
        DisjointSets fans(0);                                       // the faces' fans around one vertex
        for (std::size_t v = range.begin(); v != range.end(); ++v) {
          CountEdges(&stars, v, &c);
          const std::int32_t deg = stars.start[v + 1] - stars.start[v];
          if (deg <= 1) continue;
          const bool split = deg <= kSmallFan ? SmallStarIsSplit(stars, tris, v, deg)
                                              : LargeStarIsSplit(stars, tris, v, deg, &around, &fans);
          if (split) ++c.non_manifold_vertices;
        }
        return c;
      },
      [](Counts a, const Counts& b) {
        a.border += b.border;
        a.non_manifold_edges += b.non_manifold_edges;
        a.inconsistent += b.inconsistent;
        a.non_manifold_vertices += b.non_manifold_vertices;
        return a;
      });
}

// 6. Components: vertex-connected pieces.
std::int64_t CountComponents(std::size_t n_points, const std::vector<std::array<std::int32_t, 3>>& tris) {
  std::int64_t components = 0;
  DisjointSets pieces(n_points);
  std::vector<char> used(n_points, 0);
  for (const auto& t : tris) {
    pieces.Join(t[0], t[1]);
    pieces.Join(t[0], t[2]);
    used[t[0]] = used[t[1]] = used[t[2]] = 1;
  }
  for (std::size_t v = 0; v < n_points; ++v) components += used[v] && pieces.Find(v) == v;
  return components;
}

// The closed, manifold and outward verdicts and their reasons, from the
// counts and volume in *report; `has_triangles`: any non-degenerate one.
void JudgeTopology(bool has_triangles, MeshReport* report) {
  MeshReport& r = *report;
  r.closed = has_triangles && r.border_edges == 0;
  if (!has_triangles)
    r.closed_reason = "mesh has no non-degenerate triangles";
  else if (!r.closed)
    r.closed_reason = "mesh has " + Plural(r.border_edges, "border edge") + " (not watertight)";
  r.manifold = r.non_manifold_edges == 0 && r.non_manifold_vertices == 0;
  if (!r.manifold) {
    r.manifold_reason = "mesh has " + Plural(r.non_manifold_edges, "non-manifold edge") + " (3+ faces) and " +
                        Plural(r.non_manifold_vertices, "non-manifold vertex", "non-manifold vertices") +
                        " (several fans)";
  }
  if (!r.closed) {
    r.outward = false;
    r.outward_reason = "orientation undefined: mesh is not closed";
  } else if (r.non_manifold_edges > 0) {
    r.outward_reason = "orientation undefined: mesh has " + Plural(r.non_manifold_edges, "non-manifold edge");
  } else if (r.inconsistent_edges > 0) {
    r.outward_reason = "faces are not consistently oriented (" + Plural(r.inconsistent_edges, "edge") +
                       " traversed the same way by both faces)";
  } else if (!(r.volume > 0)) {
    r.outward_reason = "signed volume " + std::to_string(r.volume) + " mm^3 is not positive (normals point inward)";
  } else {
    r.outward = true;
  }
}

// 7. Self-intersection (CGAL), on the non-collinear triangles (at least one
// triangle): the intersecting pairs up to options.max_intersecting_pairs.
void CheckSelfIntersection(const std::vector<std::array<double, 3>>& points, const MergedTriangles& merged,
                           const InspectOptions& options, MeshReport* report) {
  const std::vector<std::array<std::int32_t, 3>>& tris = merged.tris;
  std::vector<Point> soup_points;
  soup_points.reserve(points.size());
  for (const auto& p : points) soup_points.emplace_back(p[0], p[1], p[2]);
  std::vector<std::vector<std::size_t>> soup;
  soup.reserve(tris.size());
  for (std::size_t f = 0; f < tris.size(); ++f) {
    if (merged.collinear[f]) continue;
    soup.push_back({static_cast<std::size_t>(tris[f][0]), static_cast<std::size_t>(tris[f][1]),
                    static_cast<std::size_t>(tris[f][2])});
  }
  PMP::orient_polygon_soup(soup_points, soup);  // splits non-manifold vertices
  SurfaceMesh sm;
  PMP::polygon_soup_to_polygon_mesh(soup_points, soup, sm);
  std::int64_t count = 0;
  const std::int64_t cap = std::max<std::int64_t>(1, options.max_intersecting_pairs);
  try {
    PMP::self_intersections(sm, PairCounter{&count, cap});
  } catch (const PairLimitReached&) {
    report->intersecting_pairs_capped = true;
  }
  report->intersecting_pairs = count;
  report->self_intersecting = count > 0;
  if (report->self_intersecting) {
    report->self_intersection_reason = std::string("mesh has ") +
                                       (report->intersecting_pairs_capped ? "at least " : "") + Plural(count, "pair") +
                                       " of intersecting triangles";
  }
}

}  // namespace

std::string MeshReport::Reasons() const {
  std::string out;
  for (const std::string* r : {&closed_reason, &manifold_reason, &self_intersection_reason, &outward_reason}) {
    if (r->empty()) continue;
    if (!out.empty()) out += "; ";
    out += *r;
  }
  return out;
}

MeshReport InspectMesh(const TriangleMesh& mesh, const InspectOptions& options) {
  MeshReport report;
  // 1. Merge vertices with bit-identical coordinates.
  const MergedVertices vertices = MergeVertices(mesh);
  const std::vector<std::array<double, 3>>& points = vertices.points;
  report.merged_vertices = static_cast<std::int64_t>(mesh.vertices.size() - points.size());
  // 2. Triangles over merged vertices; drop repeated corners, mark collinear ones.
  const MergedTriangles merged = MergeTriangles(mesh, vertices, &report);
  const std::vector<std::array<std::int32_t, 3>>& tris = merged.tris;
  // 3. Measures: bbox of used vertices, area, signed volume about the bbox centre.
  Measure(points, tris, &report);
  // 4, 5. Edges and vertex fans.
  const Counts counts = CountTopology(points.size(), tris);
  report.border_edges += counts.border;
  report.non_manifold_edges += counts.non_manifold_edges;
  report.inconsistent_edges += counts.inconsistent;
  report.non_manifold_vertices += counts.non_manifold_vertices;
  // 6. Components.
  report.components += CountComponents(points.size(), tris);
  // Verdicts.
  JudgeTopology(!tris.empty(), &report);
  // 7. Self-intersection.
  if (options.check_self_intersection && !tris.empty()) CheckSelfIntersection(points, merged, options, &report);
  return report;
}

}  // namespace fabatlas::mesh
