// The signed distance of a closed convex triangle mesh
// (fabatlas/geometry/convex_mesh_distance.h), from its face planes.
#include "fabatlas/geometry/convex_mesh_distance.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

namespace fabatlas::geometry {
namespace {

// A closed convex triangle mesh as its face planes, each with the triangles
// lying in it: the signed distance of a convex polytope is exact from these
// (inside: the largest plane value; outside: the nearest point lies on a
// face whose plane the point is in front of).
struct ConvexFace {
  Vec3 n;    // unit outward normal
  double d;  // n . x = d on the face
  std::vector<std::array<Vec3, 3>> triangles;
};

// Closest distance from p to triangle abc (Ericson, "Real-Time Collision
// Detection", Sec. 5.1.5, by Voronoi regions).
double DistanceToTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  auto sub = [](const Vec3& u, const Vec3& v) { return Vec3{u[0] - v[0], u[1] - v[1], u[2] - v[2]}; };
  auto dot = [](const Vec3& u, const Vec3& v) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; };
  auto at = [&](const Vec3& o, const Vec3& e1, double s, const Vec3& e2, double t) {
    const Vec3 q{o[0] + s * e1[0] + t * e2[0], o[1] + s * e1[1] + t * e2[1], o[2] + s * e1[2] + t * e2[2]};
    const Vec3 d = sub(p, q);
    return std::sqrt(dot(d, d));
  };
  const Vec3 ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return at(a, ab, 0, ac, 0);
  const Vec3 bp = sub(p, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return at(a, ab, 1, ac, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return at(a, ab, d1 / (d1 - d3), ac, 0);
  const Vec3 cp = sub(p, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return at(a, ab, 0, ac, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return at(a, ab, 0, ac, d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return at(a, ab, 1 - w, ac, w);
  }
  const double den = 1 / (va + vb + vc);
  return at(a, ab, vb * den, ac, vc * den);
}

// Meshes up to this many triangles are tested for being closed and convex
// (the test costs planes x vertices).
constexpr size_t kMaxConvexTestTriangles = 20000;

// The faces of m when m is closed (every edge shared by exactly two
// triangles) and convex (every vertex on or behind every face plane, within
// 1e-9 of the mesh's size); empty otherwise.
std::vector<ConvexFace> ConvexFaces(const mesh::TriangleMesh& m) {
  if (m.triangles.size() < 4 || m.triangles.size() > kMaxConvexTestTriangles) return {};
  std::vector<std::pair<std::int64_t, std::int64_t>> edges;
  edges.reserve(3 * m.triangles.size());
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) {
      std::int64_t u = t[k], v = t[(k + 1) % 3];
      if (u == v) return {};
      edges.emplace_back(std::min(u, v), std::max(u, v));
    }
  std::sort(edges.begin(), edges.end());
  for (size_t i = 0; i < edges.size(); i += 2)
    if (i + 1 >= edges.size() || edges[i] != edges[i + 1] || (i + 2 < edges.size() && edges[i + 2] == edges[i]))
      return {};
  Vec3 centre{0, 0, 0}, lo = m.vertices[0], hi = m.vertices[0];
  for (const auto& v : m.vertices)
    for (int k = 0; k < 3; ++k) {
      centre[k] += v[k] / static_cast<double>(m.vertices.size());
      lo[k] = std::min(lo[k], v[k]);
      hi[k] = std::max(hi[k], v[k]);
    }
  const double size = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  const double tol = 1e-9 * size;
  std::vector<ConvexFace> faces;
  for (const auto& t : m.triangles) {
    const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
    const Vec3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    Vec3 n{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 1e-12 * size * size)) continue;  // a degenerate triangle adds no face
    for (double& x : n) x /= len;
    double d = n[0] * a[0] + n[1] * a[1] + n[2] * a[2];
    if (n[0] * centre[0] + n[1] * centre[1] + n[2] * centre[2] > d) {
      for (double& x : n) x = -x;
      d = -d;
    }
    ConvexFace* face = nullptr;
    for (auto& f : faces)
      if (std::abs(f.d - d) <= tol && f.n[0] * n[0] + f.n[1] * n[1] + f.n[2] * n[2] > 1 - 1e-12) face = &f;
    if (!face) {
      faces.push_back({n, d, {}});
      face = &faces.back();
    }
    face->triangles.push_back({a, b, c});
  }
  if (faces.size() < 4) return {};
  for (const auto& f : faces)
    for (const auto& v : m.vertices)
      if (f.n[0] * v[0] + f.n[1] * v[1] + f.n[2] * v[2] - f.d > tol) return {};
  return faces;
}

// Exact within `band` (mm); beyond it the largest plane value, a lower bound.
double ConvexDistance(const std::vector<ConvexFace>& faces, double band, double x, double y, double z) {
  double inside = -std::numeric_limits<double>::infinity();
  for (const auto& f : faces) inside = std::max(inside, f.n[0] * x + f.n[1] * y + f.n[2] * z - f.d);
  if (inside <= 0 || inside >= band) return inside;
  double best = std::numeric_limits<double>::infinity();
  const Vec3 p{x, y, z};
  for (const auto& f : faces) {
    if (f.n[0] * x + f.n[1] * y + f.n[2] * z - f.d <= 0) continue;
    for (const auto& t : f.triangles) best = std::min(best, DistanceToTriangle(p, t[0], t[1], t[2]));
  }
  return best;
}

}  // namespace

DistanceFunction ConvexMeshDistance(const mesh::TriangleMesh& m, double exact_within) {
  for (const auto& t : m.triangles)
    for (std::int32_t v : t)
      if (v < 0 || static_cast<size_t>(v) >= m.vertices.size()) return {};
  std::vector<ConvexFace> faces = ConvexFaces(m);
  if (faces.empty()) return {};
  // An axis-aligned box (six faces, normals along the axes; every OpenSCAD
  // cube under a translation or scale): the same distance in closed form,
  // exact everywhere (a lower bound beyond the band, as required), at a
  // fraction of the triangle tests' cost.
  Vec3 lo{}, hi{};
  int sides = 0;
  for (const auto& f : faces)
    for (int k = 0; k < 3; ++k) {
      if (f.n[k] == 1 && f.n[(k + 1) % 3] == 0 && f.n[(k + 2) % 3] == 0) hi[k] = f.d, sides += 1 << (2 * k);
      if (f.n[k] == -1 && f.n[(k + 1) % 3] == 0 && f.n[(k + 2) % 3] == 0) lo[k] = -f.d, sides += 2 << (2 * k);
    }
  if (faces.size() == 6 && sides == 0b111111) return BoxDistance{lo, hi};
  return [faces = std::move(faces), exact_within](double x, double y, double z) {
    return ConvexDistance(faces, exact_within, x, y, z);
  };
}

}  // namespace fabatlas::geometry
