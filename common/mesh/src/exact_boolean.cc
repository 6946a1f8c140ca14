// Exact mesh booleans, convex hulls and Minkowski sums with CGAL (see
// exact_boolean.h): corefinement on Surface_mesh<Epeck>, Nef polyhedra as the
// fallback.
#include "fabatlas/mesh/exact_boolean.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <cstdint>
#include <map>
#include <numeric>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Nef_polyhedron_3.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polyhedron_3.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/convert_nef_polyhedron_to_polygon_mesh.h>
#include <CGAL/convex_decomposition_3.h>
#include <CGAL/convex_hull_3.h>

#include "fabatlas/error.h"
#include "fabatlas/mesh/enclosed_volume.h"

namespace fabatlas::mesh {
namespace {

using Kernel = CGAL::Exact_predicates_exact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
using Nef = CGAL::Nef_polyhedron_3<Kernel>;
namespace PMP = CGAL::Polygon_mesh_processing;

// An exact operand or intermediate result: a closed surface mesh, or a Nef
// polyhedron where the exact result is not a 2-manifold.
struct Exact {
  SurfaceMesh mesh;
  std::optional<Nef> nef;
  CGAL::Bbox_3 box;
  bool empty = true;
};

Nef NefOf(const Exact& e);

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

void AppendExact(const Exact& e, TriangleMesh& out) {
  if (e.empty) return;
  if (!e.nef) {
    AppendMesh(e.mesh, out);
    return;
  }
  std::vector<Point> points;
  std::vector<std::vector<std::size_t>> polygons;
  CGAL::convert_nef_polyhedron_to_polygon_soup(*e.nef, points, polygons, /*triangulate_all_faces=*/true);
  const auto base = static_cast<std::int32_t>(out.vertices.size());
  for (const Point& p : points)
    out.vertices.push_back({CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())});
  for (const auto& f : polygons)
    if (f.size() == 3)
      out.triangles.push_back({base + static_cast<std::int32_t>(f[0]), base + static_cast<std::int32_t>(f[1]),
                               base + static_cast<std::int32_t>(f[2])});
}

// The Nef polyhedron of a closed mesh. CGAL builds each closed shell as a
// solid whatever its orientation, so a cavity (an inward shell inside an
// outward one) would come out filled: the outward shells are joined and the
// inward ones, turned outward, taken away.
Nef NefOf(const Exact& e) {
  if (e.nef) return *e.nef;
  std::vector<SurfaceMesh> shells;
  PMP::split_connected_components(e.mesh, shells);
  if (shells.size() <= 1) return Nef(e.mesh);
  Nef solid, cavities;
  for (SurfaceMesh& shell : shells) {
    double six = 0;
    for (auto f : shell.faces()) {
      std::array<Point, 3> p;
      int i = 0;
      for (auto v : CGAL::vertices_around_face(shell.halfedge(f), shell))
        if (i < 3) p[i++] = shell.point(v);
      six += CGAL::to_double(CGAL::determinant(p[0] - CGAL::ORIGIN, p[1] - CGAL::ORIGIN, p[2] - CGAL::ORIGIN));
    }
    if (six < 0) {
      PMP::reverse_face_orientations(shell);
      cavities += Nef(shell);
    } else {
      solid += Nef(shell);
    }
  }
  return solid - cavities;
}

Exact OfNef(Nef nef) {
  Exact out;
  out.empty = nef.is_empty();
  if (out.empty) return out;
  if (nef.is_simple()) {
    CGAL::convert_nef_polyhedron_to_polygon_mesh(nef, out.mesh, /*triangulate_all_faces=*/true);
    out.box = PMP::bbox(out.mesh);
  } else {
    std::vector<Point> points;
    std::vector<std::vector<std::size_t>> polygons;
    CGAL::convert_nef_polyhedron_to_polygon_soup(nef, points, polygons, true);
    out.box = CGAL::bbox_3(points.begin(), points.end());
    out.nef = std::move(nef);
  }
  return out;
}

bool Meet(const CGAL::Bbox_3& a, const CGAL::Bbox_3& b) { return CGAL::do_overlap(a, b); }

using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;
using FloatMesh = CGAL::Surface_mesh<Epick::Point_3>;

// The same surface with its points rounded to doubles (From: back to exact
// points, which doubles are exactly).
template <typename Out, typename In, typename MakePoint>
Out Copied(const In& m, MakePoint make) {
  Out out;
  std::vector<typename Out::Vertex_index> to(m.number_of_vertices() + m.number_of_removed_vertices());
  for (auto v : m.vertices()) to[v.idx()] = out.add_vertex(make(m.point(v)));
  std::vector<typename Out::Vertex_index> face;
  for (auto f : m.faces()) {
    face.clear();
    for (auto v : CGAL::vertices_around_face(m.halfedge(f), m)) face.push_back(to[v.idx()]);
    out.add_face(face);
  }
  return out;
}
FloatMesh ToFloat(const SurfaceMesh& m) {
  return Copied<FloatMesh>(m, [](const Point& p) {
    return Epick::Point_3(CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z()));
  });
}
SurfaceMesh FromFloat(const FloatMesh& m) {
  return Copied<SurfaceMesh>(m, [](const Epick::Point_3& p) { return Point(p.x(), p.y(), p.z()); });
}

// Corefinement with exact predicates and constructions in doubles: the
// intersection points are rounded once as they are made, which is all a
// result rounded to doubles keeps. Taken when the result is closed and does
// not touch itself (rounding can make it), else nullopt. Coplanar faces with
// many crossings (two 360-gon caps in one plane) cost seconds in the exact
// kernel and milliseconds here.
std::optional<SurfaceMesh> FloatCorefinement(BooleanOp op, const SurfaceMesh& a, const SurfaceMesh& b) {
  try {
    FloatMesh fa = ToFloat(a), fb = ToFloat(b), out;
    const auto np = CGAL::parameters::throw_on_self_intersection(true);
    const bool ok = op == BooleanOp::kUnion        ? PMP::corefine_and_compute_union(fa, fb, out, np, np)
                    : op == BooleanOp::kDifference ? PMP::corefine_and_compute_difference(fa, fb, out, np, np)
                                                   : PMP::corefine_and_compute_intersection(fa, fb, out, np, np);
    if (!ok || !CGAL::is_closed(out) || PMP::does_self_intersect(out)) return std::nullopt;
    return FromFloat(out);
  } catch (...) {
    return std::nullopt;
  }
}

// a op b, both non-empty: corefinement (in doubles, then exact), else Nef.
Exact Apply(BooleanOp op, const Exact& a, const Exact& b, std::size_t b_index, const BooleanOptions& options,
            BooleanSummary& summary) {
  std::string why;
  if (!a.nef && !b.nef) {
    if (std::optional<SurfaceMesh> fast = FloatCorefinement(op, a.mesh, b.mesh)) {
      ++summary.corefinements;
      Exact r;
      r.empty = fast->number_of_faces() == 0;
      if (!r.empty) r.box = PMP::bbox(*fast);
      r.mesh = std::move(*fast);
      return r;
    }
    if (!options.exact_fallbacks)
      throw InputError(std::string("exact ") + BooleanOpName(op) + " needs exact constructions");
    ++summary.exact_corefinements;
    SurfaceMesh ma = a.mesh, mb = b.mesh, out;
    bool ok = false;
    try {
      const auto np = CGAL::parameters::throw_on_self_intersection(true);
      ok = op == BooleanOp::kUnion        ? PMP::corefine_and_compute_union(ma, mb, out, np, np)
           : op == BooleanOp::kDifference ? PMP::corefine_and_compute_difference(ma, mb, out, np, np)
                                          : PMP::corefine_and_compute_intersection(ma, mb, out, np, np);
      why = "no manifold result";
    } catch (const PMP::Corefinement::Self_intersection_exception&) {
      why = "an operand touches itself near the intersection";
    } catch (const std::exception& e) {
      why = e.what();
    }
    ++summary.corefinements;
    if (ok) {
      Exact r;
      r.empty = out.number_of_faces() == 0;
      if (!r.empty) r.box = PMP::bbox(out);
      r.mesh = std::move(out);
      return r;
    }
  } else {
    why = "an operand is not a 2-manifold";
  }
  if (!options.exact_fallbacks)
    throw InputError(std::string("exact ") + BooleanOpName(op) + " needs Nef polyhedra (" + why + ")");
  ++summary.nef;
  if (summary.nef_why.empty()) summary.nef_why = why;
  // Nef polyhedra take only valid solids (CGAL does not check: a mesh that
  // touches itself can crash the construction).
  for (const Exact* e : {&b, &a})
    if (!e->nef && PMP::does_self_intersect(e->mesh))
      throw InputError("exact boolean operand " + (e == &b ? std::to_string(b_index) : std::string("0")) +
                       (e == &a && b_index > 1 ? " (with the operands before " + std::to_string(b_index) + ")" : "") +
                       " intersects itself (" + BooleanOpName(op) + ": " + why + ")");
  try {
    const Nef na = NefOf(a), nb = NefOf(b);
    return OfNef(op == BooleanOp::kUnion ? na + nb : op == BooleanOp::kDifference ? na - nb : na * nb);
  } catch (const std::exception& e) {
    throw InputError(std::string("exact ") + BooleanOpName(op) + " could not be computed (" + why +
                     "; Nef polyhedra: " + e.what() + ")");
  }
}

// Groups of operands whose bounding boxes meet, transitively.
std::vector<std::vector<std::size_t>> TouchingGroups(const std::vector<Exact>& in) {
  std::vector<std::size_t> parent(in.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (std::size_t i = 0; i < in.size(); ++i)
    for (std::size_t j = i + 1; j < in.size(); ++j)
      if (Meet(in[i].box, in[j].box)) parent[find(j)] = find(i);
  std::map<std::size_t, std::vector<std::size_t>> groups;
  for (std::size_t i = 0; i < in.size(); ++i) groups[find(i)].push_back(i);
  std::vector<std::vector<std::size_t>> out;
  for (auto& [_, g] : groups) out.push_back(std::move(g));
  return out;
}

std::size_t FaceCount(const Exact& e) {
  if (e.empty) return 0;
  return e.nef ? e.nef->number_of_facets() : e.mesh.number_of_faces();
}

// The union of operands whose bounding boxes meet transitively (index: each
// one's index among the boolean's operands, for messages), as pieces whose
// boxes are apart. The two smallest operands (by faces) whose boxes meet are
// joined first, and the result goes back among the operands, as Manifold
// orders a union's operands by size: a corefinement costs about the faces
// of both operands, so small operands meet each other before they meet a
// large one, which is not rebuilt once per operand of the node (issue1069
// of OpenSCAD's corpus, a Minkowski sum's union of 24 hulls: 2.3x less
// time). An operand whose box meets no other piece's is a piece of the
// result as it is.
std::vector<Exact> UnionOfTouching(std::vector<Exact> pieces, std::vector<std::size_t> index,
                                   const BooleanOptions& options, BooleanSummary& summary) {
  std::vector<Exact> done;
  while (!pieces.empty()) {
    std::size_t smallest = 0;
    for (std::size_t k = 1; k < pieces.size(); ++k)
      if (FaceCount(pieces[k]) < FaceCount(pieces[smallest])) smallest = k;
    std::optional<std::size_t> partner;
    for (std::size_t k = 0; k < pieces.size(); ++k)
      if (k != smallest && Meet(pieces[smallest].box, pieces[k].box) &&
          (!partner || FaceCount(pieces[k]) < FaceCount(pieces[*partner])))
        partner = k;
    if (!partner) {  // apart from every other piece, and from all they will join into
      done.push_back(std::move(pieces[smallest]));
      pieces.erase(pieces.begin() + static_cast<std::ptrdiff_t>(smallest));
      index.erase(index.begin() + static_cast<std::ptrdiff_t>(smallest));
      continue;
    }
    // The earlier operand first, as the operands were given.
    const std::size_t first = index[smallest] < index[*partner] ? smallest : *partner;
    const std::size_t second = first == smallest ? *partner : smallest;
    Exact joined = Apply(BooleanOp::kUnion, pieces[first], pieces[second], index[second], options, summary);
    index[first] = std::min(index[first], index[second]);
    pieces[first] = std::move(joined);
    pieces.erase(pieces.begin() + static_cast<std::ptrdiff_t>(second));
    index.erase(index.begin() + static_cast<std::ptrdiff_t>(second));
  }
  return done;
}

// The same mesh with its vertices sorted by coordinates and its triangles
// by their vertices (each starting at its least, orientation kept): CGAL
// lists a result's vertices and faces in an order that depends on the
// addresses of its internal boxes (Box_intersection_d's ids), so equal
// results came out in different orders between runs, and sums over them
// (volumes, ΔG, the level set built from them) differed in the last bits.
TriangleMesh Canonical(TriangleMesh m) {
  std::vector<std::int32_t> order(m.vertices.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) { return m.vertices[a] < m.vertices[b]; });
  std::vector<std::int32_t> rank(m.vertices.size());
  TriangleMesh out;
  out.vertices.reserve(m.vertices.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    rank[order[i]] = static_cast<std::int32_t>(i);
    out.vertices.push_back(m.vertices[order[i]]);
  }
  out.triangles.reserve(m.triangles.size());
  for (const auto& t : m.triangles) {
    std::array<std::int32_t, 3> r{rank[t[0]], rank[t[1]], rank[t[2]]};
    const int k = r[0] <= r[1] && r[0] <= r[2] ? 0 : r[1] <= r[2] ? 1 : 2;
    out.triangles.push_back({r[k], r[(k + 1) % 3], r[(k + 2) % 3]});
  }
  std::sort(out.triangles.begin(), out.triangles.end());
  return out;
}

}  // namespace

const char* BooleanOpName(BooleanOp op) {
  switch (op) {
    case BooleanOp::kUnion:
      return "union";
    case BooleanOp::kDifference:
      return "difference";
    case BooleanOp::kIntersection:
      return "intersection";
  }
  return "union";
}

namespace {
TriangleMesh UnorderedBoolean(BooleanOp op, const std::vector<TriangleMesh>& operands, BooleanSummary* summary_out,
                              const BooleanOptions& options);
}  // namespace

TriangleMesh ExactBoolean(BooleanOp op, const std::vector<TriangleMesh>& operands, BooleanSummary* summary_out,
                          const BooleanOptions& options) {
  return Canonical(UnorderedBoolean(op, operands, summary_out, options));
}

namespace {
// The union of the operands `in`: operands apart from all others join the
// result as they are; each group of touching ones is united (UnionOfTouching).
TriangleMesh UnionAll(std::vector<Exact>& in, const BooleanOptions& options, BooleanSummary& summary) {
  TriangleMesh out;
  std::vector<Exact> present;
  std::vector<std::size_t> present_index;  // each one's index among the operands
  for (std::size_t i = 0; i < in.size(); ++i)
    if (!in[i].empty) {
      present.push_back(std::move(in[i]));
      present_index.push_back(i);
    }
  // Operands apart from all others join the result as they are.
  for (const auto& group : TouchingGroups(present)) {
    summary.disjoint += group.size() == 1 && present.size() > 1;
    std::vector<Exact> pieces;
    std::vector<std::size_t> pieces_index;
    for (std::size_t k : group) {
      pieces.push_back(std::move(present[k]));
      pieces_index.push_back(present_index[k]);
    }
    for (const Exact& piece : UnionOfTouching(std::move(pieces), pieces_index, options, summary))
      AppendExact(piece, out);
  }
  return out;
}

// The operands taken away (`away`, their operand indices `away_index`),
// joined into one when every piece of their union is a surface mesh (apart
// pieces side by side in one mesh); left as they are otherwise.
void JoinSubtrahends(std::vector<Exact>& away, std::vector<std::size_t>& away_index, const BooleanOptions& options,
                     BooleanSummary& summary) {
  std::vector<Exact> pieces;
  for (const auto& group : TouchingGroups(away)) {
    std::vector<Exact> members;
    std::vector<std::size_t> members_index;
    for (std::size_t k : group) {
      members.push_back(away[k]);
      members_index.push_back(away_index[k]);
    }
    for (Exact& piece : UnionOfTouching(std::move(members), members_index, options, summary))
      pieces.push_back(std::move(piece));
  }
  if (std::none_of(pieces.begin(), pieces.end(), [](const Exact& e) { return e.nef.has_value(); })) {
    Exact joined = std::move(pieces[0]);
    for (std::size_t k = 1; k < pieces.size(); ++k) {
      joined.mesh += pieces[k].mesh;
      joined.box += pieces[k].box;
    }
    away.clear();
    away.push_back(std::move(joined));
    away_index.resize(1);
  }
}

// in[0] minus the other operands (in[0] not empty).
// a - b1 - b2 - ... = a - (b1 | b2 | ...): the operands taken away are
// joined first (apart ones cost nothing) and taken away at once, so the
// first operand is corefined once, not once per operand (camera-tests of
// OpenSCAD's corpus, a sphere minus three crossing cylinders: 8-10x
// less time). Where a piece of their union is a Nef polyhedron, one
// operand at a time.
TriangleMesh DifferenceAll(std::vector<Exact>& in, const BooleanOptions& options, BooleanSummary& summary) {
  TriangleMesh out;
  Exact acc = std::move(in[0]);
  std::vector<Exact> away;
  std::vector<std::size_t> away_index;
  for (std::size_t i = 1; i < in.size(); ++i) {
    if (in[i].empty || !Meet(acc.box, in[i].box)) {
      ++summary.disjoint;
      continue;  // nothing to take away
    }
    away.push_back(std::move(in[i]));
    away_index.push_back(i);
  }
  if (away.size() > 1) JoinSubtrahends(away, away_index, options, summary);
  for (std::size_t k = 0; k < away.size() && !acc.empty; ++k)
    acc = Apply(BooleanOp::kDifference, acc, away[k], away_index[k], options, summary);
  AppendExact(acc, out);
  return out;
}

TriangleMesh UnorderedBoolean(BooleanOp op, const std::vector<TriangleMesh>& operands, BooleanSummary* summary_out,
                              const BooleanOptions& options) {
  BooleanSummary local;
  BooleanSummary& summary = summary_out ? *summary_out : local;
  std::vector<Exact> in;
  in.reserve(operands.size());
  for (std::size_t i = 0; i < operands.size(); ++i) in.push_back(ToExact(operands[i], i, options));
  TriangleMesh out;
  if (in.empty()) return out;
  if (op == BooleanOp::kUnion) return UnionAll(in, options, summary);
  if (op == BooleanOp::kDifference && !in[0].empty) return DifferenceAll(in, options, summary);
  Exact acc = std::move(in[0]);
  for (std::size_t i = 1; i < in.size() && !acc.empty; ++i) {
    if (in[i].empty || !Meet(acc.box, in[i].box)) {
      ++summary.disjoint;
      if (op == BooleanOp::kIntersection) return out;  // nothing in common
      continue;                                        // nothing to take away
    }
    acc = Apply(op, acc, in[i], i, options, summary);
  }
  AppendExact(acc, out);
  return out;
}

}  // namespace

TriangleMesh ConvexHull(const std::vector<std::array<double, 3>>& points) {
  using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;
  std::vector<Epick::Point_3> p;
  p.reserve(points.size());
  for (const auto& v : points)
    if (std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2])) p.emplace_back(v[0], v[1], v[2]);
  // The points span a volume when four of them are not coplanar.
  std::size_t second = 1, third = 0, fourth = 0;
  while (second < p.size() && p[second] == p[0]) ++second;
  for (std::size_t i = second + 1; i < p.size() && !third; ++i)
    if (!CGAL::collinear(p[0], p[second], p[i])) third = i;
  for (std::size_t i = third + 1; third && i < p.size() && !fourth; ++i)
    if (CGAL::orientation(p[0], p[second], p[third], p[i]) != CGAL::COPLANAR) fourth = i;
  TriangleMesh out;
  if (!fourth) return out;
  CGAL::Surface_mesh<Epick::Point_3> hull;
  CGAL::convex_hull_3(p.begin(), p.end(), hull);
  std::vector<std::int32_t> index(hull.number_of_vertices() + hull.number_of_removed_vertices(), -1);
  for (auto v : hull.vertices()) {
    index[v.idx()] = static_cast<std::int32_t>(out.vertices.size());
    const auto& q = hull.point(v);
    out.vertices.push_back({q.x(), q.y(), q.z()});
  }
  for (auto f : hull.faces()) {
    std::array<std::int32_t, 3> tri{};
    int i = 0;
    for (auto v : CGAL::vertices_around_face(hull.halfedge(f), hull))
      if (i < 3) tri[i++] = index[v.idx()];
    out.triangles.push_back(tri);
  }
  return out;
}

namespace {

using ConvexPart = std::vector<std::array<double, 3>>;

// A closed mesh's convex parts, each as its vertices.
std::vector<ConvexPart> ConvexParts(const TriangleMesh& m) {
  const TriangleMesh hull = ConvexHull(m.vertices);
  const double volume = std::abs(EnclosedVolume(m)), hull_volume = std::abs(EnclosedVolume(hull));
  if (hull_volume <= volume * (1 + 1e-9)) return {hull.vertices};  // convex
  Exact e = ToExact(m, 0, BooleanOptions{});
  Nef nef = NefOf(e);
  CGAL::convex_decomposition_3(nef);
  std::vector<ConvexPart> parts;
  auto volume_it = nef.volumes_begin();
  for (++volume_it; volume_it != nef.volumes_end(); ++volume_it) {
    if (!volume_it->mark()) continue;
    CGAL::Polyhedron_3<Kernel> part;
    nef.convert_inner_shell_to_polyhedron(volume_it->shells_begin(), part);
    ConvexPart points;
    for (auto v = part.vertices_begin(); v != part.vertices_end(); ++v)
      points.push_back(
          {CGAL::to_double(v->point().x()), CGAL::to_double(v->point().y()), CGAL::to_double(v->point().z())});
    if (!points.empty()) parts.push_back(std::move(points));
  }
  return parts;
}

}  // namespace

TriangleMesh MinkowskiSum(const std::vector<TriangleMesh>& operands, BooleanSummary* summary) {
  std::vector<ConvexPart> acc;
  bool first = true;
  for (const TriangleMesh& m : operands) {
    if (m.triangles.empty()) continue;
    std::vector<ConvexPart> parts = ConvexParts(m);
    if (first) {
      acc = std::move(parts);
      first = false;
      continue;
    }
    std::vector<ConvexPart> sums;
    for (const ConvexPart& a : acc)
      for (const ConvexPart& b : parts) {
        ConvexPart s;
        s.reserve(a.size() * b.size());
        for (const auto& p : a)
          for (const auto& q : b) s.push_back({p[0] + q[0], p[1] + q[1], p[2] + q[2]});
        sums.push_back(ConvexHull(s).vertices);
      }
    acc = std::move(sums);
  }
  std::vector<TriangleMesh> hulls;
  for (const ConvexPart& part : acc) {
    TriangleMesh h = ConvexHull(part);
    if (!h.triangles.empty()) hulls.push_back(std::move(h));
  }
  if (hulls.size() == 1) return hulls[0];
  return ExactBoolean(BooleanOp::kUnion, hulls, summary);
}

}  // namespace fabatlas::mesh
