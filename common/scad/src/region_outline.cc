// The outline and triangulation of a planar region (fabatlas/scad/region_outline.h).
#include "fabatlas/scad/region_outline.h"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <map>

namespace fabatlas::scad {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
using Fb0 = CGAL::Constrained_triangulation_face_base_2<K>;
using Fb = CGAL::Triangulation_face_base_with_info_2<bool, K, Fb0>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::Exact_predicates_tag>;

}  // namespace

Region2 ResolveRegion(const std::vector<Loop>& loops, const std::function<bool(const Point2&)>& inside) {
  Cdt cdt;
  for (const Loop& loop : loops) {
    if (loop.size() < 3) continue;
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const Point2& a = loop[i];
      const Point2& b = loop[(i + 1) % loop.size()];
      if (a != b) cdt.insert_constraint(K::Point_2(a[0], a[1]), K::Point_2(b[0], b[1]));
    }
  }
  Region2 r;
  for (auto v = cdt.finite_vertices_begin(); v != cdt.finite_vertices_end(); ++v) {
    v->info() = static_cast<int>(r.points.size());
    r.points.push_back({v->point().x(), v->point().y()});
  }
  for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->info() = false;
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    const int a = f->vertex(0)->info(), b = f->vertex(1)->info(), c = f->vertex(2)->info();
    const Point2 centroid{(r.points[a][0] + r.points[b][0] + r.points[c][0]) / 3,
                          (r.points[a][1] + r.points[b][1] + r.points[c][1]) / 3};
    f->info() = inside(centroid);
    if (f->info()) r.triangles.push_back({a, b, c});  // CGAL's faces are counter-clockwise
  }
  // Boundary edges between a kept face and a dropped (or infinite) one,
  // directed with the kept face on the left: from vertex ccw(i) to cw(i).
  std::multimap<int, int> next;
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    if (!f->info()) continue;
    for (int i = 0; i < 3; ++i) {
      const auto g = f->neighbor(i);
      if (!cdt.is_infinite(g) && g->info()) continue;
      next.emplace(f->vertex(Cdt::ccw(i))->info(), f->vertex(Cdt::cw(i))->info());
    }
  }
  // Chain them into loops (at a vertex where the region touches itself, any
  // pairing closes the loops), then drop collinear vertices.
  while (!next.empty()) {
    std::vector<int> loop;
    auto it = next.begin();
    const int start = it->first;
    int at = start;
    while (it != next.end()) {
      loop.push_back(at);
      at = it->second;
      next.erase(it);
      if (at == start) break;
      it = next.find(at);
    }
    std::vector<int> kept;
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const Point2& prev = r.points[loop[(i + loop.size() - 1) % loop.size()]];
      const Point2& p = r.points[loop[i]];
      const Point2& q = r.points[loop[(i + 1) % loop.size()]];
      const bool turns = CGAL::orientation(K::Point_2(prev[0], prev[1]), K::Point_2(p[0], p[1]),
                                           K::Point_2(q[0], q[1])) != CGAL::COLLINEAR;
      const bool spike = (q[0] - p[0]) * (p[0] - prev[0]) + (q[1] - p[1]) * (p[1] - prev[1]) < 0;
      if (turns || spike) kept.push_back(loop[i]);
    }
    if (kept.size() >= 3) r.loops.push_back(std::move(kept));
  }
  return r;
}

}  // namespace fabatlas::scad
