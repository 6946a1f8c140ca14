// OpenSCAD's primitives as polygon meshes (fabatlas/scad/primitive_mesh.h).
#include "fabatlas/scad/primitive_mesh.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <set>

namespace fabatlas::scad {
namespace {

using mesh::TriangleMesh;
using V3 = std::array<double, 3>;

double SinDeg(double a) { return SinDegrees(a); }
double CosDeg(double a) { return CosDegrees(a); }

// An angle in degrees folded into [0, 90] (x -> its reference angle), with
// the signs of its sine and cosine.
struct Folded {
  double x;
  bool negative_sin, negative_cos;
};

Folded Fold(double x) {
  x -= 360.0 * std::floor(x / 360.0);
  Folded f{x, x >= 180.0, false};
  if (f.negative_sin) f.x -= 180.0;
  f.negative_cos = f.negative_sin;
  if (f.x > 90.0) {
    f.x = 180.0 - f.x;
    f.negative_cos = !f.negative_cos;
  }
  return f;
}

constexpr double kDegree = std::numbers::pi / 180;
constexpr double kSqrt3Over2 = 0.86602540378443864676;

void AddFan(TriangleMesh& m, const std::vector<int>& face, bool flip) {
  for (std::size_t k = 1; k + 1 < face.size(); ++k) {
    if (flip)
      m.triangles.push_back({face[0], face[k + 1], face[k]});
    else
      m.triangles.push_back({face[0], face[k], face[k + 1]});
  }
}

// A regular polygon's cap (vertices counter-clockwise from angle 0, as
// OpenSCAD's rings) as a strip of parallel chords: vertex j joined to
// vertex n - j, each band between two chords split along one diagonal. The
// same surface as OpenSCAD's one polygon face. Two caps in one plane (a
// hole drilled through a disc, a cup's bottom) then cross only where a
// chord of one passes through a band of the other, O(n) crossings, where
// fans from one rim vertex cross each other's chords everywhere, O(n^2):
// two 360-gon caps cost 6 s of the corefinement's exact arithmetic as fans
// (a fan from the centre, its spokes nearly collinear with the other's,
// 17 s at 96 sides), 0.1 s as strips (docs/openscad.md).
void AddStripCap(TriangleMesh& m, const std::vector<int>& ring, bool flip) {
  const int n = static_cast<int>(ring.size());
  if (n < 3) return;
  auto add = [&](int a, int b, int c) {
    if (flip)
      m.triangles.push_back({ring[a], ring[c], ring[b]});
    else
      m.triangles.push_back({ring[a], ring[b], ring[c]});
  };
  add(0, 1, n - 1);
  for (int lo = 1, hi = n - 1; hi - lo > 1; ++lo, --hi) {
    if (hi - lo == 2) {
      add(lo, lo + 1, hi);
      break;
    }
    add(lo, lo + 1, hi - 1);
    add(lo, hi - 1, hi);
  }
}

double SignedArea(const Loop& p) {
  double a = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Point2& u = p[i];
    const Point2& v = p[(i + 1) % p.size()];
    a += u[0] * v[1] - v[0] * u[1];
  }
  return 0.5 * a;
}

double Cross(const Point2& o, const Point2& a, const Point2& b) {
  return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

// A top scaled to zero in one axis is a segment: the walls' top edges
// overlap along it. Each triangle edge on the segment is split at the top
// vertices inside it (a fan from the opposite vertex), so that every piece
// of the segment is an edge of the triangles on both sides of it.
void SplitAtTopVertices(TriangleMesh& m, const std::map<std::array<double, 3>, int>& top) {
  std::map<int, double> along;                            // top vertex -> its coordinate along the segment
  for (const auto& [p, i] : top) along[i] = p[0] + p[1];  // one of x, y is 0
  std::vector<std::pair<double, int>> sorted;
  for (const auto& [i, t] : along) sorted.push_back({t, i});
  std::sort(sorted.begin(), sorted.end());
  std::vector<std::array<int, 3>> out;
  for (const auto& t : m.triangles) {
    int k = 0;
    while (k < 3 && !(along.count(t[k]) && along.count(t[(k + 1) % 3]))) ++k;
    if (k == 3) {
      out.push_back(t);
      continue;
    }
    const int u = t[k], v = t[(k + 1) % 3], apex = t[(k + 2) % 3];
    const double tu = along[u], tv = along[v];
    std::vector<int> chain{u};
    for (const auto& [tw, w] : sorted)
      if (std::min(tu, tv) < tw && tw < std::max(tu, tv)) chain.push_back(w);
    if (tu > tv) std::reverse(chain.begin() + 1, chain.end());
    chain.push_back(v);
    for (std::size_t i = 0; i + 1 < chain.size(); ++i) out.push_back({chain[i], chain[i + 1], apex});
  }
  // Walls folded onto each other along the segment give a triangle and its
  // reverse: a fin of no volume, dropped.
  std::map<std::array<int, 3>, int> count;  // rotated to start at the least vertex
  auto key = [](std::array<int, 3> t) {
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    return t;
  };
  for (const auto& t : out) ++count[key(t)];
  m.triangles.clear();
  for (const auto& t : out) {
    const auto r = key({t[0], t[2], t[1]});
    auto it = count.find(r);
    if (it != count.end() && it->second > 0) {
      --it->second;  // cancels one copy of the reverse
      --count[key(t)];
      continue;
    }
    if (count[key(t)] > 0) m.triangles.push_back(t);
  }
}

}  // namespace

double SinDegrees(double a) {
  if (!std::isfinite(a) || std::abs(a) >= 360.0 * 4503599627370496.0) return std::nan("");
  const Folded f = Fold(a);
  double v;
  if (f.x == 30)
    v = 0.5;
  else if (f.x == 45)
    v = std::numbers::sqrt2 / 2;
  else if (f.x == 60)
    v = kSqrt3Over2;
  else
    v = f.x < 45 ? std::sin(f.x * kDegree) : std::cos((90 - f.x) * kDegree);
  return f.negative_sin ? -v : v;
}

double CosDegrees(double a) {
  if (!std::isfinite(a) || std::abs(a) >= 360.0 * 4503599627370496.0) return std::nan("");
  const Folded f = Fold(a);
  double v;
  if (f.x == 60)
    v = 0.5;
  else if (f.x == 45)
    v = std::numbers::sqrt2 / 2;
  else if (f.x == 30)
    v = kSqrt3Over2;
  else
    v = f.x > 45 ? std::sin((90 - f.x) * kDegree) : std::cos(f.x * kDegree);
  return f.negative_cos ? -v : v;
}

int Fragments(double r, double fn, double fs, double fa) {
  if (r < 1e-6 || !std::isfinite(fn)) return 3;  // $fn = inf gives a triangle, as in OpenSCAD 2021.01
  if (fn > 0) return fn >= 3 ? static_cast<int>(fn) : 3;
  return static_cast<int>(std::ceil(std::max(std::min(360.0 / fa, r * 2 * std::numbers::pi / fs), 5.0)));
}

TriangleMesh CubeMesh(const std::array<double, 3>& s, bool center) {
  TriangleMesh m;
  const V3 lo = center ? V3{-s[0] / 2, -s[1] / 2, -s[2] / 2} : V3{0, 0, 0};
  for (int k = 0; k < 8; ++k)
    m.vertices.push_back({lo[0] + (k & 1 ? s[0] : 0), lo[1] + (k & 2 ? s[1] : 0), lo[2] + (k & 4 ? s[2] : 0)});
  const int q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : q) AddFan(m, {f[0], f[1], f[2], f[3]}, false);
  return m;
}

TriangleMesh SphereMesh(double r, int fragments) {
  TriangleMesh m;
  const int rings = (fragments + 1) / 2;
  for (int i = 0; i < rings; ++i) {
    const double phi = 180.0 * (i + 0.5) / rings;
    const double rr = r * SinDeg(phi), z = r * CosDeg(phi);
    for (int j = 0; j < fragments; ++j) {
      const double a = 360.0 * j / fragments;
      m.vertices.push_back({rr * CosDeg(a), rr * SinDeg(a), z});
    }
  }
  auto at = [&](int ring, int j) { return ring * fragments + (j % fragments); };
  std::vector<int> top, bottom;
  for (int j = 0; j < fragments; ++j) {
    top.push_back(at(0, j));
    bottom.push_back(at(rings - 1, j));
  }
  AddStripCap(m, top, true);
  AddStripCap(m, bottom, false);
  for (int i = 0; i + 1 < rings; ++i)
    for (int j = 0; j < fragments; ++j) AddFan(m, {at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)}, false);
  for (auto& t : m.triangles) std::swap(t[1], t[2]);  // outward: the rings run north to south
  return m;
}

TriangleMesh CylinderMesh(double h, double r1, double r2, bool center, int fragments) {
  TriangleMesh m;
  const double z1 = center ? -h / 2 : 0, z2 = z1 + h;
  for (int ring = 0; ring < 2; ++ring) {
    const double r = ring ? r2 : r1, z = ring ? z2 : z1;
    for (int j = 0; j < fragments; ++j) {
      const double a = 360.0 * j / fragments;
      m.vertices.push_back({r * CosDeg(a), r * SinDeg(a), z});
    }
  }
  std::vector<int> bottom, top;
  for (int j = 0; j < fragments; ++j) {
    bottom.push_back(j);
    top.push_back(fragments + j);
    const int k = (j + 1) % fragments;
    AddFan(m, {j, k, fragments + k, fragments + j}, false);
  }
  AddStripCap(m, bottom, true);
  AddStripCap(m, top, false);
  return m;
}

// The diagonal OpenSCAD 2021.01 splits a quad face along (true: corners 0
// and 2, false: 1 and 3). It tessellates faces with libtess2's constrained
// Delaunay triangulation: the face projected along its normal's largest axis
// (in single precision), a monotone triangulation in sweep order (s, then t),
// then a diagonal flipped when its two opposite angles sum to pi + 0.01 or
// more. For a convex quad the monotone triangulation joins the two middle
// vertices in sweep order when the first and last are opposite, else the
// last to the first's other neighbour; a concave quad has one diagonal. The
// choice decides the solid only when the quad is not planar (issue1867.scad).
bool QuadDiagonalIsZeroTwo(const std::vector<V3>& points, const std::vector<int>& f, const V3& normal) {
  int k = 0;
  for (int j = 1; j < 3; ++j)
    if (std::abs(normal[j]) > std::abs(normal[k])) k = j;
  Loop q;
  for (int i : f) q.push_back({static_cast<float>(points[i][(k + 1) % 3]), static_cast<float>(points[i][(k + 2) % 3])});
  if (SignedArea(q) < 0)
    for (auto& p : q) p[1] = -p[1];  // counter-clockwise in (s, t), as libtess2 orients it
  for (int i = 0; i < 4; ++i)
    if (Cross(q[(i + 3) % 4], q[i], q[(i + 1) % 4]) <= 0) return i % 2 == 0;  // reflex corner i: its diagonal
  std::array<int, 4> order = {0, 1, 2, 3};
  std::sort(order.begin(), order.end(), [&](int a, int b) { return q[a] < q[b]; });
  const int first = order[0], last = order[3];
  // First and last opposite: the middles' diagonal; adjacent: last joined
  // to first's other neighbour, which lies opposite last.
  bool zero_two = (first + 2) % 4 == last ? first % 2 == 1 : last % 2 == 0;
  auto angle = [&](int at, int a, int b) {
    const double ux = q[a][0] - q[at][0], uy = q[a][1] - q[at][1], vx = q[b][0] - q[at][0], vy = q[b][1] - q[at][1];
    double c = (ux * vx + uy * vy) / (std::hypot(ux, uy) * std::hypot(vx, vy));
    return std::acos(std::clamp(c, -1.0, 1.0));
  };
  const int a = zero_two ? 0 : 1, b = a + 1, c = (a + 2) % 4, d = (a + 3) % 4;
  if (angle(b, c, a) + angle(d, a, c) >= std::numbers::pi + 0.01) zero_two = !zero_two;
  return zero_two;
}

TriangleMesh PolyhedronMesh(const std::vector<std::array<double, 3>>& points,
                            const std::vector<std::vector<int>>& faces) {
  TriangleMesh m;
  m.vertices = points;
  for (const auto& f : faces) {
    if (f.size() == 3) AddFan(m, f, false);
    if (f.size() <= 3) continue;
    // A polygon face may be concave (polyhedron-concave-test.scad's
    // hexagons): ear-clipped in its plane, seen along its normal's largest
    // axis (Newell's normal), so its triangles keep the face's winding.
    std::array<double, 3> normal{0, 0, 0};
    for (std::size_t i = 0; i < f.size(); ++i) {
      const auto& a = points[f[i]];
      const auto& b = points[f[(i + 1) % f.size()]];
      normal[0] += (a[1] - b[1]) * (a[2] + b[2]);
      normal[1] += (a[2] - b[2]) * (a[0] + b[0]);
      normal[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    if (f.size() == 4 && std::set<int>(f.begin(), f.end()).size() == 4) {
      if (QuadDiagonalIsZeroTwo(points, f, normal))
        AddFan(m, f, false);
      else
        AddFan(m, {f[1], f[2], f[3], f[0]}, false);
      continue;
    }
    int k = 0;
    for (int j = 1; j < 3; ++j)
      if (std::abs(normal[j]) > std::abs(normal[k])) k = j;
    int u = (k + 1) % 3, v = (k + 2) % 3;
    if (normal[k] < 0) std::swap(u, v);
    Loop loop;
    for (int i : f) loop.push_back({points[i][u], points[i][v]});
    for (const auto& t : TriangulateLoop(loop)) m.triangles.push_back({f[t[0]], f[t[1]], f[t[2]]});
  }
  return m;
}

bool ApproximatelyConvex(const TriangleMesh& m) {
  if (m.triangles.empty()) return false;
  std::map<std::pair<int, int>, std::size_t> edge_of;  // directed edge -> triangle
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int j = 0; j < 3; ++j)
      if (!edge_of.emplace(std::make_pair(m.triangles[t][j], m.triangles[t][(j + 1) % 3]), t).second) return false;
  std::vector<V3> normal(m.triangles.size());
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const V3 &a = m.vertices[m.triangles[t][0]], &b = m.vertices[m.triangles[t][1]], &c = m.vertices[m.triangles[t][2]];
    const V3 u = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    normal[t] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  }
  const double threshold = std::cos(0.1 * std::numbers::pi / 180);
  std::vector<bool> reached(m.triangles.size(), false);
  std::vector<std::size_t> queue = {0};
  reached[0] = true;
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int j = 0; j < 3; ++j) {
      auto it = edge_of.find({m.triangles[t][(j + 1) % 3], m.triangles[t][j]});
      if (it == edge_of.end()) return false;  // not closed
      const std::size_t o = it->second;
      const V3& p = m.vertices[m.triangles[t][(j + 2) % 3]];
      const V3& q = m.vertices[m.triangles[o][0]];
      const V3& n = normal[o];
      if (n[0] * (p[0] - q[0]) + n[1] * (p[1] - q[1]) + n[2] * (p[2] - q[2]) > 0) {  // folds inward
        const V3& w = normal[t];
        const double cosine =
            (n[0] * w[0] + n[1] * w[1] + n[2] * w[2]) /
            std::sqrt((n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]));
        if (!(cosine >= threshold)) return false;
      }
    }
  while (!queue.empty()) {
    const std::size_t t = queue.back();
    queue.pop_back();
    for (int j = 0; j < 3; ++j) {
      const std::size_t o = edge_of.at({m.triangles[t][(j + 1) % 3], m.triangles[t][j]});
      if (!reached[o]) reached[o] = true, queue.push_back(o);
    }
  }
  return std::all_of(reached.begin(), reached.end(), [](bool r) { return r; });
}

Loop CircleLoop(double r, int fragments) {
  Loop p;
  for (int j = 0; j < fragments; ++j) {
    const double a = 360.0 * j / fragments;
    p.push_back({r * CosDeg(a), r * SinDeg(a)});
  }
  return p;
}

Loop SquareLoop(double x, double y, bool center) {
  const double x0 = center ? -x / 2 : 0, y0 = center ? -y / 2 : 0;
  return {{x0, y0}, {x0 + x, y0}, {x0 + x, y0 + y}, {x0, y0 + y}};
}

std::vector<std::array<int, 3>> TriangulateLoop(const Loop& loop) {
  std::vector<std::array<int, 3>> tris;
  const int n = static_cast<int>(loop.size());
  if (n < 3) return tris;
  std::vector<int> idx(n);
  for (int i = 0; i < n; ++i) idx[i] = i;
  if (SignedArea(loop) < 0) std::reverse(idx.begin(), idx.end());
  // Ear clipping (O(n^2)); a degenerate remainder is closed by a fan.
  int guard = 0;
  while (idx.size() > 3 && guard++ < 4 * n * n) {
    bool clipped = false;
    const int m = static_cast<int>(idx.size());
    for (int i = 0; i < m; ++i) {
      const int a = idx[(i + m - 1) % m], b = idx[i], c = idx[(i + 1) % m];
      if (Cross(loop[a], loop[b], loop[c]) <= 0) continue;  // reflex or collinear
      bool inside = false;
      for (int k = 0; k < m && !inside; ++k) {
        const int p = idx[k];
        if (p == a || p == b || p == c) continue;
        inside = Cross(loop[a], loop[b], loop[p]) >= 0 && Cross(loop[b], loop[c], loop[p]) >= 0 &&
                 Cross(loop[c], loop[a], loop[p]) >= 0;
      }
      if (inside) continue;
      tris.push_back({a, b, c});
      idx.erase(idx.begin() + i);
      clipped = true;
      break;
    }
    if (!clipped) break;
  }
  for (std::size_t k = 1; k + 1 < idx.size(); ++k) tris.push_back({idx[0], idx[k], idx[k + 1]});
  return tris;
}

TriangleMesh LinearExtrudeMesh(const Region2& region, double height, bool center, double twist, int slices,
                               const Point2& scale) {
  TriangleMesh m;
  const int n = static_cast<int>(region.points.size());
  slices = std::max(1, slices);
  const double z0 = center ? -height / 2 : 0, z1 = center ? height / 2 : height;
  const bool zero_top = scale[0] == 0 || scale[1] == 0;
  // Layer s: rotated by -twist * s / slices, then scaled (OpenSCAD's order
  // and arithmetic). A top scaled to zero collapses to a point or a
  // segment: its coinciding vertices are one vertex.
  std::vector<int> id;  // layer vertex -> mesh vertex
  std::map<std::array<double, 3>, int> top;
  for (int s = 0; s <= slices; ++s) {
    const double a = -(twist * s / slices);  // positive twist turns clockwise going up
    const double sx = 1 - (1 - scale[0]) * s / slices, sy = 1 - (1 - scale[1]) * s / slices;
    const double c = CosDeg(a), sn = SinDeg(a);
    const double m00 = sx * c, m01 = sx * -sn, m10 = sy * sn, m11 = sy * c;
    const double z = z0 + (z1 - z0) * s / slices;
    for (const Point2& p : region.points) {
      const std::array<double, 3> v{m00 * p[0] + m01 * p[1], m10 * p[0] + m11 * p[1], z};
      if (s == slices && zero_top) {
        auto [it, fresh] = top.emplace(v, static_cast<int>(m.vertices.size()));
        if (fresh) m.vertices.push_back(v);
        id.push_back(it->second);
      } else {
        id.push_back(static_cast<int>(m.vertices.size()));
        m.vertices.push_back(v);
      }
    }
  }
  auto add = [&](int a, int b, int c) {
    a = id[a], b = id[b], c = id[c];
    if (a != b && b != c && c != a) m.triangles.push_back({a, b, c});
  };
  for (const auto& t : region.triangles) add(t[0], t[2], t[1]);
  if (!zero_top)
    for (const auto& t : region.triangles) add(slices * n + t[0], slices * n + t[1], slices * n + t[2]);
  // OpenSCAD's comparison of the diagonals' lengths: equal within 10 ppm of
  // their mean.
  auto shorter = [&](int i, int j, int k, int l) {  // -1: |ij| < |kl|, 0: equal, 1: longer
    auto length = [&](int u, int v) {
      const auto& p = m.vertices[id[u]];
      const auto& q = m.vertices[id[v]];
      return std::hypot(p[0] - q[0], p[1] - q[1]);
    };
    const double l1 = length(i, j), l2 = length(k, l);
    return 2 * std::abs(l1 - l2) * 1e5 > l1 + l2 ? (l1 < l2 ? -1 : 1) : 0;
  };
  for (const auto& loop : region.loops) {
    const int k = static_cast<int>(loop.size());
    Loop points;
    for (int i : loop) points.push_back(region.points[i]);
    // Equal diagonals (an edge on a line through the axis): OpenSCAD splits
    // along the one from the edge's start up to its end when the twist is
    // positive, the other one when it is zero or negative, and the other way
    // round on holes.
    const bool hole = SignedArea(points) < 0;
    const bool tie_start_up = hole == (twist <= 0);
    for (int s = 0; s < slices; ++s) {
      // A top scaled to zero takes the other diagonal (no flat "ears").
      const bool invert = zero_top && s + 1 == slices;
      for (int i = 0; i < k; ++i) {
        const int p1 = s * n + loop[i], c1 = s * n + loop[(i + 1) % k];  // this layer: previous, current vertex
        const int p2 = p1 + n, c2 = c1 + n;                              // the layer above
        const int d = shorter(p1, c2, c1, p2);
        const bool start_up = (d == -1 || (d == 0 && tie_start_up)) != invert;
        if (start_up) {  // diagonal p1-c2
          add(p1, c1, c2);
          add(p1, c2, p2);
        } else {  // diagonal c1-p2
          add(p1, c1, p2);
          add(c1, c2, p2);
        }
      }
    }
  }
  if (zero_top && top.size() > 1) SplitAtTopVertices(m, top);
  return m;
}

int ExtrudeSlices(double r_sqr, double delta_sqr, double height, double twist, const Point2& scale, double fn,
                  double fs, double fa) {
  constexpr double kFine = 1e-8;  // OpenSCAD's GRID_FINE
  twist = std::abs(twist);
  const bool uniform = scale[0] == scale[1];
  auto diagonal = [&] {
    if (std::sqrt(delta_sqr) < kFine || !std::isfinite(fn)) return 1;
    if (fn > 0) return std::max(static_cast<int>(fn), 1);
    return std::max(static_cast<int>(std::ceil(std::sqrt(delta_sqr + height * height) / fs)), 1);
  };
  if (twist == 0) return uniform ? 1 : diagonal();
  auto twisted = [&] {
    const int min_slices = std::max(static_cast<int>(std::ceil(twist / 120)), 1);
    const double r = std::sqrt(r_sqr);
    if (r < kFine || !std::isfinite(fn)) return min_slices;
    if (fn > 0) return std::max(static_cast<int>(std::ceil(twist * fn / 360)), min_slices);
    const double rad = twist * std::numbers::pi / 180;
    double length;  // of the path the outermost vertex follows
    if (!uniform || scale[0] == 1) {
      const double c = height / rad;  // a helix
      length = rad * std::sqrt(r_sqr + c * c);
    } else {  // a conical spiral: a section of an Archimedes spiral, then the height
      const double sc = scale[0];
      const double end = sc > 1 ? rad * sc / (sc - 1) : rad / (1 - sc), start = end - rad;
      const double a = r / end;
      auto arc = [&](double th) { return 0.5 * a * (th * std::sqrt(1 + th * th) + std::asinh(th)); };
      const double spiral = arc(end) - arc(start);
      length = std::sqrt(spiral * spiral + height * height);
    }
    const int by_fa = static_cast<int>(std::ceil(twist / fa)), by_fs = static_cast<int>(std::ceil(length / fs));
    return std::max(std::min(by_fa, by_fs), min_slices);
  };
  return twisted();
}

TriangleMesh RotateExtrudeMesh(const Region2& region, double angle, int fragments) {
  TriangleMesh m;
  const int n = static_cast<int>(region.points.size());
  const bool closed = std::abs(angle) >= 360;
  fragments = std::max(1, fragments);
  const int rings = closed ? fragments : fragments + 1;
  // Ring r at OpenSCAD's angle a: (x sin a, x cos a, y), a = -90 + 360 r / f
  // for a full turn (starting on -x), 90 - r angle / f otherwise (on +x). A
  // point on the axis is one vertex in every ring.
  std::vector<int> id(static_cast<std::size_t>(rings) * n);
  for (int r = 0; r < rings; ++r) {
    const double a = closed ? -90 + r * 360.0 / fragments : 90 - r * angle / fragments;
    for (int i = 0; i < n; ++i) {
      const Point2& p = region.points[i];
      if (p[0] == 0 && r > 0) {
        id[r * n + i] = id[i];
        continue;
      }
      id[r * n + i] = static_cast<int>(m.vertices.size());
      m.vertices.push_back({p[0] * SinDeg(a), p[0] * CosDeg(a), p[1]});
    }
  }
  auto add = [&](int a, int b, int c) {
    a = id[a], b = id[b], c = id[c];
    if (a != b && b != c && c != a) m.triangles.push_back({a, b, c});
  };
  for (const auto& loop : region.loops) {
    const int k = static_cast<int>(loop.size());
    for (int r = 0; r < fragments; ++r) {
      const int r2 = closed ? (r + 1) % fragments : r + 1;
      for (int i = 0; i < k; ++i) {
        const int a = loop[i], b = loop[(i + 1) % k];
        add(r * n + a, r2 * n + b, r * n + b);
        add(r * n + a, r2 * n + a, r2 * n + b);
      }
    }
  }
  if (!closed)
    for (const auto& t : region.triangles) {
      add(t[0], t[1], t[2]);
      add(fragments * n + t[0], fragments * n + t[2], fragments * n + t[1]);
    }
  // The walls' orientation depends on the side of the axis and the sense of
  // the turn: make the solid's volume positive (outward triangles).
  double volume = 0;
  for (const auto& t : m.triangles) {
    const auto& p = m.vertices[t[0]];
    const auto& q = m.vertices[t[1]];
    const auto& w = m.vertices[t[2]];
    volume +=
        p[0] * (q[1] * w[2] - q[2] * w[1]) - p[1] * (q[0] * w[2] - q[2] * w[0]) + p[2] * (q[0] * w[1] - q[1] * w[0]);
  }
  if (volume < 0)
    for (auto& t : m.triangles) std::swap(t[1], t[2]);
  return m;
}

TriangleMesh RotateExtrudeMesh(const Loop& loop, double angle, int fragments) {
  Region2 region;
  region.points = loop;
  region.triangles = TriangulateLoop(loop);
  std::vector<int> indices(loop.size());
  for (std::size_t i = 0; i < loop.size(); ++i) indices[i] = static_cast<int>(i);
  if (SignedArea(loop) < 0) std::reverse(indices.begin(), indices.end());
  region.loops.push_back(std::move(indices));
  return RotateExtrudeMesh(region, angle, fragments);
}

}  // namespace fabatlas::scad
