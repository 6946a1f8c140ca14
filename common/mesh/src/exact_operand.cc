// A closed triangle mesh as an exact solid (exact_solid.h) and back:
// coincident vertices merged, shells touching along edges split apart,
// oriented outward with CGAL's polygon soup repair.
#include <CGAL/Polygon_mesh_processing/bbox.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "exact_solid.h"
#include "fabatlas/error.h"
#include "fabatlas/mesh/enclosed_volume.h"

namespace fabatlas::mesh::internal {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;

using Edge = std::pair<std::size_t, std::size_t>;  // vertex indices, lower first

// Corners (face * 3 + position) of a triangle soup, joined in groups when
// two faces meet at that vertex across an edge; each group of joined
// corners keeps one copy of its vertex.
class CornerGroups {
 public:
  explicit CornerGroups(const std::vector<std::vector<std::size_t>>& faces) : faces_(faces), parent_(faces.size() * 3) {
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  std::size_t Find(std::size_t i) {
    while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
    return i;
  }
  // Joins faces f and g at both ends of their common edge.
  void Join(const Edge& edge, std::size_t f, std::size_t g) {
    parent_[Find(Corner(g, edge.first))] = Find(Corner(f, edge.first));
    parent_[Find(Corner(g, edge.second))] = Find(Corner(f, edge.second));
  }

 private:
  std::size_t Corner(std::size_t f, std::size_t v) const {
    return f * 3 + static_cast<std::size_t>(std::find(faces_[f].begin(), faces_[f].end(), v) - faces_[f].begin());
  }
  const std::vector<std::vector<std::size_t>>& faces_;
  std::vector<std::size_t> parent_;
};

using Vec = std::array<double, 3>;

Vec Cross(const Vec& u, const Vec& v) {
  return Vec{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
}
double Dot(const Vec& u, const Vec& v) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; }

// The triangles `list` (an even number, more than two) around an edge sorted
// by angle around it, each joined in `groups` with its neighbour across the
// material between them. False when some triangle gets no partner or more
// than one.
bool PairSheetsAroundEdge(const std::vector<Point>& points, const std::vector<std::vector<std::size_t>>& faces,
                          const Edge& edge, const std::vector<std::size_t>& list, CornerGroups& groups) {
  auto vec = [&](std::size_t from, std::size_t to) {
    const Point &p = points[from], &q = points[to];
    return Vec{CGAL::to_double(q.x() - p.x()), CGAL::to_double(q.y() - p.y()), CGAL::to_double(q.z() - p.z())};
  };
  const auto d = vec(edge.first, edge.second);
  const double len = std::sqrt(Dot(d, d));
  // A frame around the edge: e1 any unit vector across it, e2 = d x e1.
  Vec e1 = std::abs(d[0]) < 0.9 * len ? Vec{1, 0, 0} : Vec{0, 1, 0};
  const double along = Dot(e1, d) / (len * len);
  for (int k = 0; k < 3; ++k) e1[k] -= along * d[k];
  auto e2 = Cross(d, e1);
  for (double& c : e2) c /= len;
  struct Sheet {
    double angle;
    std::size_t face;
    Vec normal;
  };
  std::vector<Sheet> sheets;
  for (std::size_t f : list) {
    std::size_t w = faces[f][0];
    for (std::size_t v : faces[f])
      if (v != edge.first && v != edge.second) w = v;
    const auto r = vec(edge.first, w);
    sheets.push_back(
        {std::atan2(Dot(r, e2), Dot(r, e1)), f, Cross(vec(faces[f][0], faces[f][1]), vec(faces[f][0], faces[f][2]))});
  }
  std::sort(sheets.begin(), sheets.end(), [](const Sheet& a, const Sheet& b) { return a.angle < b.angle; });
  std::vector<int> partners(sheets.size(), 0);
  for (std::size_t k = 0; k < sheets.size(); ++k) {
    const std::size_t next = (k + 1) % sheets.size();
    double mid = 0.5 * (sheets[k].angle + sheets[next].angle);
    if (next == 0) mid += std::numbers::pi;  // the wedge across the angle's cut
    Vec m{};
    for (int c = 0; c < 3; ++c) m[c] = std::cos(mid) * e1[c] + std::sin(mid) * e2[c];
    if (Dot(sheets[k].normal, m) < 0) {  // material between sheet k and the next
      groups.Join(edge, sheets[k].face, sheets[next].face);
      ++partners[k];
      ++partners[next];
    }
  }
  return std::none_of(partners.begin(), partners.end(), [](int n) { return n != 1; });
}

// Solids meeting along an edge (two cubes sharing only an edge, as Nef
// results and OpenSCAD's STL have them) leave that edge with four or more
// triangles. Each such edge's triangles are sorted around it and each is
// paired with its neighbour across the material between them; triangles
// joined by ordinary edges and by these pairs form closed shells, and each
// shell gets its own copies of its vertices, so the soup becomes closed
// 2-manifold shells that touch along the shared edges. False when no edge
// has more than two triangles, or the triangles around one cannot be paired.
bool SplitShellsAtSharedEdges(std::vector<Point>& points, std::vector<std::vector<std::size_t>>& faces) {
  std::map<Edge, std::vector<std::size_t>> around;  // undirected edge -> faces
  for (std::size_t f = 0; f < faces.size(); ++f)
    for (int j = 0; j < 3; ++j) {
      const std::size_t a = faces[f][j], b = faces[f][(j + 1) % 3];
      around[{std::min(a, b), std::max(a, b)}].push_back(f);
    }
  CornerGroups groups(faces);
  bool shared = false;
  for (const auto& [edge, list] : around) {
    if (list.size() <= 2) {
      if (list.size() == 2) groups.Join(edge, list[0], list[1]);
      continue;
    }
    if (list.size() % 2) return false;
    shared = true;
    if (!PairSheetsAroundEdge(points, faces, edge, list, groups)) return false;
  }
  if (!shared) return false;
  std::map<std::size_t, std::size_t> copy;  // corner group -> new point
  std::vector<Point> copies;
  std::vector<std::vector<std::size_t>> split = faces;
  for (std::size_t f = 0; f < faces.size(); ++f)
    for (int j = 0; j < 3; ++j) {
      auto [it, added] = copy.try_emplace(groups.Find(f * 3 + j), copies.size());
      if (added) copies.push_back(points[faces[f][j]]);
      split[f][j] = it->second;
    }
  faces = std::move(split);
  points = std::move(copies);
  return true;
}

}  // namespace

Exact ToExact(const TriangleMesh& m, std::size_t index, const BooleanOptions& options) {
  Exact out;
  if (m.triangles.empty()) return out;
  const std::string name = "exact boolean operand " + std::to_string(index);
  // Vertices at bit-identical coordinates are one point (a cone's apex that
  // OpenSCAD's faceting repeats, an STL's soup); a triangle that then
  // repeats a point has no area and is not part of the boundary.
  std::vector<Point> points;
  std::vector<std::size_t> merged(m.vertices.size());
  std::map<std::array<double, 3>, std::size_t> at;
  for (std::size_t i = 0; i < m.vertices.size(); ++i) {
    const auto& v = m.vertices[i];
    if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]))
      throw InputError(name + " has a vertex that is not a finite number");
    auto [it, added] = at.try_emplace(v, points.size());
    if (added) points.emplace_back(v[0], v[1], v[2]);
    merged[i] = it->second;
  }
  std::vector<std::vector<std::size_t>> faces;
  faces.reserve(m.triangles.size());
  for (const auto& t : m.triangles) {
    for (std::int32_t v : t)
      if (v < 0 || static_cast<std::size_t>(v) >= m.vertices.size())
        throw InputError(name + " has a triangle with a missing vertex");
    const std::size_t a = merged[t[0]], b = merged[t[1]], c = merged[t[2]];
    if (a == b || b == c || a == c) continue;
    faces.push_back({a, b, c});
  }
  // A vertex or edge shared by several sheets (two cubes meeting at an
  // edge, as Nef results and OpenSCAD's STL have them) is split per sheet.
  const bool touching = !PMP::is_polygon_soup_a_polygon_mesh(faces) && SplitShellsAtSharedEdges(points, faces);
  if (!PMP::is_polygon_soup_a_polygon_mesh(faces)) PMP::orient_polygon_soup(points, faces);
  if (!PMP::is_polygon_soup_a_polygon_mesh(faces)) throw InputError(name + " is not a manifold mesh");
  PMP::polygon_soup_to_polygon_mesh(points, faces, out.mesh);
  if (!CGAL::is_closed(out.mesh)) throw InputError(name + " is not closed");
  if (EnclosedVolume(m) < 0) PMP::reverse_face_orientations(out.mesh);
  out.box = PMP::bbox(out.mesh);
  out.empty = out.mesh.number_of_faces() == 0;
  // Shells touching along edges are one solid only as a Nef polyhedron.
  if (touching && !out.empty) {
    if (!options.exact_fallbacks) throw InputError(name + " has shells touching along an edge (Nef polyhedra needed)");
    out.nef = NefOf(out);
  }
  return out;
}

namespace {

void AppendMesh(const SurfaceMesh& m, TriangleMesh& out) {
  std::vector<std::int32_t> index(m.number_of_vertices() + m.number_of_removed_vertices(), -1);
  for (auto v : m.vertices()) {
    index[v.idx()] = static_cast<std::int32_t>(out.vertices.size());
    const Point& p = m.point(v);
    out.vertices.push_back({CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())});
  }
  for (auto f : m.faces()) {
    std::array<std::int32_t, 3> tri{};
    int i = 0;
    for (auto v : CGAL::vertices_around_face(m.halfedge(f), m)) {
      if (i < 3) tri[i] = index[v.idx()];
      ++i;
    }
    if (i == 3) out.triangles.push_back(tri);
  }
}

}  // namespace

void AppendExact(const Exact& e, TriangleMesh& out) {
  if (e.empty) return;
  if (e.nef)
    AppendNef(*e.nef, out);
  else
    AppendMesh(e.mesh, out);
}

}  // namespace fabatlas::mesh::internal
