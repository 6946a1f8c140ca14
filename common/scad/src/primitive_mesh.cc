// OpenSCAD's primitives as polygon meshes (fabatlas/scad/primitive_mesh.h).
#include "fabatlas/scad/primitive_mesh.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace fabatlas::scad {
namespace {

using mesh::TriangleMesh;
using V3 = std::array<double, 3>;

double SinDeg(double a) { return std::sin(a * std::numbers::pi / 180); }
double CosDeg(double a) { return std::cos(a * std::numbers::pi / 180); }

void AddFan(TriangleMesh& m, const std::vector<int>& face, bool flip) {
  for (std::size_t k = 1; k + 1 < face.size(); ++k) {
    if (flip) m.triangles.push_back({face[0], face[k + 1], face[k]});
    else m.triangles.push_back({face[0], face[k], face[k + 1]});
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

// Adds a cap: the loop's triangulation on the ring starting at vertex `base`.
void AddCap(TriangleMesh& m, const std::vector<std::array<int, 3>>& tris, int base, bool flip) {
  for (const auto& t : tris) {
    if (flip) m.triangles.push_back({base + t[0], base + t[2], base + t[1]});
    else m.triangles.push_back({base + t[0], base + t[1], base + t[2]});
  }
}

}  // namespace

int Fragments(double r, double fn, double fs, double fa) {
  if (r < 1e-6) return 3;
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
  AddFan(m, top, true);
  AddFan(m, bottom, false);
  for (int i = 0; i + 1 < rings; ++i)
    for (int j = 0; j < fragments; ++j) AddFan(m, {at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j)}, false);
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
  AddFan(m, bottom, true);
  AddFan(m, top, false);
  return m;
}

TriangleMesh PolyhedronMesh(const std::vector<std::array<double, 3>>& points, const std::vector<std::vector<int>>& faces) {
  TriangleMesh m;
  m.vertices = points;
  for (const auto& f : faces)
    if (f.size() >= 3) AddFan(m, f, false);
  return m;
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
  const double z0 = center ? -height / 2 : 0;
  // Layer s: rotated by -twist * s / slices, then scaled (OpenSCAD's order).
  for (int s = 0; s <= slices; ++s) {
    const double t = static_cast<double>(s) / slices;
    const double a = -twist * t;  // positive twist turns clockwise going up
    const double sx = 1 + (scale[0] - 1) * t, sy = 1 + (scale[1] - 1) * t;
    for (const Point2& p : region.points)
      m.vertices.push_back({sx * (CosDeg(a) * p[0] - SinDeg(a) * p[1]), sy * (SinDeg(a) * p[0] + CosDeg(a) * p[1]),
                            z0 + height * t});
  }
  AddCap(m, region.triangles, 0, true);
  AddCap(m, region.triangles, slices * n, false);
  auto squared = [&](int i, int j) {
    const auto& u = m.vertices[i];
    const auto& v = m.vertices[j];
    return (u[0] - v[0]) * (u[0] - v[0]) + (u[1] - v[1]) * (u[1] - v[1]);
  };
  for (const auto& loop : region.loops) {
    const int k = static_cast<int>(loop.size());
    Loop points;
    for (int i : loop) points.push_back(region.points[i]);
    // Equal diagonals (an edge on a line through the axis): OpenSCAD splits
    // along the one from the edge's end up to its start when the twist is
    // negative, the other one when positive, and the other way round on holes.
    const bool tie_end_up = (twist < 0) != (SignedArea(points) < 0);
    for (int s = 0; s < slices; ++s)
      for (int i = 0; i < k; ++i) {
        const int p1 = s * n + loop[i], c1 = s * n + loop[(i + 1) % k];  // this layer: previous, current vertex
        const int p2 = p1 + n, c2 = c1 + n;                                 // the layer above
        const double d_c1p2 = squared(c1, p2), d_p1c2 = squared(p1, c2);
        const double tolerance = 1e-9 * std::max(d_c1p2, d_p1c2);
        const bool end_up = std::abs(d_c1p2 - d_p1c2) <= tolerance ? tie_end_up : d_c1p2 < d_p1c2;
        if (end_up) {
          m.triangles.push_back({p1, c1, p2});
          m.triangles.push_back({c1, c2, p2});
        } else {
          m.triangles.push_back({p1, c1, c2});
          m.triangles.push_back({p1, c2, p2});
        }
      }
  }
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
  return uniform ? twisted() : std::max(twisted(), diagonal());
}

TriangleMesh RotateExtrudeMesh(const Loop& loop, double angle, int fragments) {
  TriangleMesh m;
  const int n = static_cast<int>(loop.size());
  const bool closed = std::abs(angle) >= 360;
  fragments = std::max(1, fragments);
  const int rings = closed ? fragments : fragments + 1;
  for (int r = 0; r < rings; ++r) {
    const double a = closed ? 180 + 360.0 * r / fragments : angle * r / fragments;
    for (const Point2& p : loop) m.vertices.push_back({p[0] * CosDeg(a), p[0] * SinDeg(a), p[1]});
  }
  for (int r = 0; r < fragments; ++r) {
    const int r2 = closed ? (r + 1) % fragments : r + 1;
    for (int i = 0; i < n; ++i) {
      const int j = (i + 1) % n;
      m.triangles.push_back({r * n + i, r * n + j, r2 * n + j});
      m.triangles.push_back({r * n + i, r2 * n + j, r2 * n + i});
    }
  }
  if (!closed) {
    const auto tris = TriangulateLoop(loop);
    AddCap(m, tris, 0, true);
    AddCap(m, tris, fragments * n, false);
  }
  return m;
}

}  // namespace fabatlas::scad
