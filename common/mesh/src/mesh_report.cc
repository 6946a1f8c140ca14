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
  const std::size_t nv_in = mesh.vertices.size();
  const std::int64_t nv_signed = static_cast<std::int64_t>(nv_in);

  // 1. Merge vertices with bit-identical coordinates.
  std::vector<std::int32_t> merged(nv_in);
  std::vector<std::array<double, 3>> points;
  {
    std::vector<std::int32_t> order(nv_in);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
      return mesh.vertices[a] < mesh.vertices[b] || (mesh.vertices[a] == mesh.vertices[b] && a < b);
    });
    points.reserve(nv_in);
    for (std::size_t k = 0; k < nv_in; ++k) {
      if (k == 0 || mesh.vertices[order[k]] != mesh.vertices[order[k - 1]]) points.push_back(mesh.vertices[order[k]]);
      merged[order[k]] = static_cast<std::int32_t>(points.size() - 1);
    }
  }
  report.merged_vertices = static_cast<std::int64_t>(nv_in - points.size());

  // 2. Triangles over merged vertices; drop repeated corners, mark collinear ones.
  std::vector<std::array<std::int32_t, 3>> tris;
  std::vector<char> collinear;
  tris.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    bool in_range = true;
    for (std::int32_t v : t) in_range = in_range && v >= 0 && v < nv_signed;
    if (!in_range) continue;  // ReadMesh never produces these; ignore defensively
    const std::array<std::int32_t, 3> m{merged[t[0]], merged[t[1]], merged[t[2]]};
    if (m[0] == m[1] || m[1] == m[2] || m[0] == m[2]) {
      ++report.degenerate_triangles;
      continue;
    }
    const auto& a = points[m[0]];
    const auto& b = points[m[1]];
    const auto& c = points[m[2]];
    const bool flat = CGAL::collinear(Point(a[0], a[1], a[2]), Point(b[0], b[1], b[2]), Point(c[0], c[1], c[2]));
    if (flat) ++report.degenerate_triangles;
    tris.push_back(m);
    collinear.push_back(flat ? 1 : 0);
  }

  // 3. Measures: bbox of used vertices, area, signed volume about the bbox centre.
  if (!tris.empty()) {
    report.bbox_min = {INFINITY, INFINITY, INFINITY};
    report.bbox_max = {-INFINITY, -INFINITY, -INFINITY};
    for (const auto& t : tris) {
      for (std::int32_t v : t) {
        for (int a = 0; a < 3; ++a) {
          report.bbox_min[a] = std::min(report.bbox_min[a], points[v][a]);
          report.bbox_max[a] = std::max(report.bbox_max[a], points[v][a]);
        }
      }
    }
  }
  std::array<double, 3> centre;
  for (int a = 0; a < 3; ++a) centre[a] = 0.5 * (report.bbox_min[a] + report.bbox_max[a]);
  {
    const TriangleMesh used{points, tris};
    report.volume = EnclosedVolume(used, centre);
    report.area = SurfaceArea(used, centre);
  }

  // 4. Edges: the triangle sides (hi, forward?) listed under their lower
  //    vertex lo (a bucket per vertex, then each short bucket sorted), so
  //    equal edges are adjacent.
  // 5. Vertex manifoldness: the faces around a vertex must form one fan
  //    (connected through edges incident to that vertex).
  //    Both per vertex, over vertex ranges in parallel (TBB); the counts are
  //    sums, the same whatever the schedule.
  struct HalfEdge {
    std::int32_t hi;
    bool forward;  // traversed lo -> hi
    bool operator<(const HalfEdge& o) const { return hi < o.hi; }
  };
  std::vector<std::int32_t> first(points.size() + 1, 0);
  for (const auto& t : tris)
    for (int k = 0; k < 3; ++k) ++first[std::min(t[k], t[(k + 1) % 3]) + 1];
  std::partial_sum(first.begin(), first.end(), first.begin());
  std::vector<HalfEdge> edges(first.back());
  {
    std::vector<std::int32_t> fill(first.begin(), first.end() - 1);
    for (const auto& t : tris) {
      for (int k = 0; k < 3; ++k) {
        const std::int32_t a = t[k], b = t[(k + 1) % 3];
        edges[fill[std::min(a, b)]++] = {std::max(a, b), a < b};
      }
    }
  }
  std::vector<std::int32_t> start(points.size() + 1, 0);
  for (const auto& t : tris)
    for (std::int32_t v : t) ++start[v + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<std::int32_t> incident(start.back());
  {
    std::vector<std::int32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t f = 0; f < tris.size(); ++f)
      for (std::int32_t v : tris[f]) incident[fill[v]++] = static_cast<std::int32_t>(f);
  }
  constexpr std::int32_t kSmallFan = 16;
  struct Counts {
    std::int64_t border = 0, non_manifold_edges = 0, inconsistent = 0, non_manifold_vertices = 0;
  };
  const Counts counts = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, points.size(), 1024), Counts{},
      [&](const tbb::blocked_range<std::size_t>& range, Counts c) {
        std::vector<std::pair<std::int32_t, std::int32_t>> around;  // (other vertex, local face)
        DisjointSets fans(0);                                       // the faces' fans around one vertex
        for (std::size_t v = range.begin(); v != range.end(); ++v) {
          const auto begin = edges.begin() + first[v], end = edges.begin() + first[v + 1];
          std::sort(begin, end);
          for (auto i = begin; i != end;) {
            auto j = i;
            int forward = 0;
            while (j != end && j->hi == i->hi) forward += (j++)->forward;
            const auto n = j - i;
            if (n == 1)
              ++c.border;
            else if (n > 2)
              ++c.non_manifold_edges;
            else if (forward != 1)
              ++c.inconsistent;
            i = j;
          }
          const std::int32_t deg = start[v + 1] - start[v];
          if (deg <= 1) continue;
          if (deg <= kSmallFan) {
            // The usual vertex: faces joined pairwise when they share a
            // corner other than v, on the stack.
            std::array<std::int32_t, 2 * kSmallFan> other;
            std::array<std::int8_t, kSmallFan> fan;
            for (std::int32_t k = 0; k < deg; ++k) {
              const auto& t = tris[incident[start[v] + k]];
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
                if (other[2 * i] == other[2 * j] || other[2 * i] == other[2 * j + 1] ||
                    other[2 * i + 1] == other[2 * j] || other[2 * i + 1] == other[2 * j + 1]) {
                  const int a = find(i), b = find(j);
                  if (a != b) fan[std::max(a, b)] = static_cast<std::int8_t>(std::min(a, b));
                }
            std::int32_t roots = 0;
            for (std::int32_t k = 0; k < deg; ++k) roots += find(k) == k;
            if (roots > 1) ++c.non_manifold_vertices;
            continue;
          }
          around.clear();
          for (std::int32_t k = 0; k < deg; ++k) {
            const auto& t = tris[incident[start[v] + k]];
            for (std::int32_t w : t)
              if (w != static_cast<std::int32_t>(v)) around.push_back({w, k});
          }
          std::sort(around.begin(), around.end());
          fans.Reset(static_cast<std::size_t>(deg));
          for (std::size_t i = 1; i < around.size(); ++i)
            if (around[i].first == around[i - 1].first) fans.Join(around[i].second, around[i - 1].second);
          std::int32_t roots = 0;
          for (std::int32_t k = 0; k < deg; ++k) roots += fans.Find(k) == static_cast<std::size_t>(k);
          if (roots > 1) ++c.non_manifold_vertices;
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
  report.border_edges += counts.border;
  report.non_manifold_edges += counts.non_manifold_edges;
  report.inconsistent_edges += counts.inconsistent;
  report.non_manifold_vertices += counts.non_manifold_vertices;

  // 6. Components: vertex-connected pieces.
  {
    DisjointSets pieces(points.size());
    std::vector<char> used(points.size(), 0);
    for (const auto& t : tris) {
      pieces.Join(t[0], t[1]);
      pieces.Join(t[0], t[2]);
      used[t[0]] = used[t[1]] = used[t[2]] = 1;
    }
    for (std::size_t v = 0; v < points.size(); ++v) report.components += used[v] && pieces.Find(v) == v;
  }

  // Verdicts.
  report.closed = !tris.empty() && report.border_edges == 0;
  if (tris.empty())
    report.closed_reason = "mesh has no non-degenerate triangles";
  else if (!report.closed)
    report.closed_reason = "mesh has " + Plural(report.border_edges, "border edge") + " (not watertight)";
  report.manifold = report.non_manifold_edges == 0 && report.non_manifold_vertices == 0;
  if (!report.manifold) {
    report.manifold_reason = "mesh has " + Plural(report.non_manifold_edges, "non-manifold edge") + " (3+ faces) and " +
                             Plural(report.non_manifold_vertices, "non-manifold vertex", "non-manifold vertices") +
                             " (several fans)";
  }
  if (!report.closed) {
    report.outward = false;
    report.outward_reason = "orientation undefined: mesh is not closed";
  } else if (report.non_manifold_edges > 0) {
    report.outward_reason = "orientation undefined: mesh has " + Plural(report.non_manifold_edges, "non-manifold edge");
  } else if (report.inconsistent_edges > 0) {
    report.outward_reason = "faces are not consistently oriented (" + Plural(report.inconsistent_edges, "edge") +
                            " traversed the same way by both faces)";
  } else if (!(report.volume > 0)) {
    report.outward_reason =
        "signed volume " + std::to_string(report.volume) + " mm^3 is not positive (normals point inward)";
  } else {
    report.outward = true;
  }

  // 7. Self-intersection (CGAL), on non-collinear triangles.
  if (options.check_self_intersection && !tris.empty()) {
    std::vector<Point> soup_points;
    soup_points.reserve(points.size());
    for (const auto& p : points) soup_points.emplace_back(p[0], p[1], p[2]);
    std::vector<std::vector<std::size_t>> soup;
    soup.reserve(tris.size());
    for (std::size_t f = 0; f < tris.size(); ++f) {
      if (collinear[f]) continue;
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
      report.intersecting_pairs_capped = true;
    }
    report.intersecting_pairs = count;
    report.self_intersecting = count > 0;
    if (report.self_intersecting) {
      report.self_intersection_reason = std::string("mesh has ") +
                                        (report.intersecting_pairs_capped ? "at least " : "") + Plural(count, "pair") +
                                        " of intersecting triangles";
    }
  }
  return report;
}

}  // namespace fabatlas::mesh
