// Volumes of two meshes and their intersection by vertical columns (see
// column_overlap.h).
#include "fabatlas/mesh/column_overlap.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "fabatlas/error.h"

namespace fabatlas::mesh {

namespace {

// A crossing of a column with a mesh's surface: its height and the change of
// the winding number there (+1 entering through a downward-facing triangle,
// -1 leaving through an upward-facing one).
struct Crossing {
  double z;
  int step;
};

struct Grid {
  double x0 = 0, y0 = 0, h = 1;
  long nx = 0, ny = 0;
};

// The rows of `g` each triangle of `m` may cross (its xy box), as lists of
// triangle indices per row; vertical triangles are left out (no column
// crosses them).
std::vector<std::vector<std::int32_t>> TrianglesByRow(const TriangleMesh& m, const Grid& g) {
  std::vector<std::vector<std::int32_t>> rows(static_cast<std::size_t>(g.ny));
  for (std::size_t k = 0; k < m.triangles.size(); ++k) {
    const auto& t = m.triangles[k];
    const double y0 = m.vertices[t[0]][1], y1 = m.vertices[t[1]][1], y2 = m.vertices[t[2]][1];
    const long j0 = std::max(0L, static_cast<long>(std::ceil((std::min({y0, y1, y2}) - g.y0) / g.h)));
    const long j1 = std::min(g.ny - 1, static_cast<long>(std::floor((std::max({y0, y1, y2}) - g.y0) / g.h)));
    for (long j = j0; j <= j1; ++j) rows[static_cast<std::size_t>(j)].push_back(static_cast<std::int32_t>(k));
  }
  return rows;
}

// Adds to `columns` (one per column of row j) the heights where the
// triangles `tris` of `m` cross the row's columns.
void AddRowCrossings(const TriangleMesh& m, const std::vector<std::int32_t>& tris, const Grid& g, long j,
                     std::vector<std::vector<Crossing>>* columns) {
  const double y = g.y0 + static_cast<double>(j) * g.h;
  for (const std::int32_t k : tris) {
    const auto& t = m.triangles[static_cast<std::size_t>(k)];
    const Vec3& p = m.vertices[t[0]];
    const Vec3& q = m.vertices[t[1]];
    const Vec3& r = m.vertices[t[2]];
    // Twice the signed area of the triangle's xy projection: > 0 when it faces up.
    const double area = (q[0] - p[0]) * (r[1] - p[1]) - (r[0] - p[0]) * (q[1] - p[1]);
    if (area == 0) continue;  // vertical: no column crosses it
    const long i0 = std::max(0L, static_cast<long>(std::ceil((std::min({p[0], q[0], r[0]}) - g.x0) / g.h)));
    const long i1 = std::min(g.nx - 1, static_cast<long>(std::floor((std::max({p[0], q[0], r[0]}) - g.x0) / g.h)));
    for (long i = i0; i <= i1; ++i) {
      const double x = g.x0 + static_cast<double>(i) * g.h;
      // Barycentric coordinates of (x, y) in the projection.
      const double u = ((q[0] - x) * (r[1] - y) - (r[0] - x) * (q[1] - y)) / area;
      const double v = ((r[0] - x) * (p[1] - y) - (p[0] - x) * (r[1] - y)) / area;
      const double w = 1.0 - u - v;
      if (u < 0 || v < 0 || w < 0) continue;
      // Going up, a downward-facing triangle enters the solid, an upward one leaves it.
      (*columns)[static_cast<std::size_t>(i)].push_back({u * p[2] + v * q[2] + w * r[2], area > 0 ? -1 : +1});
    }
  }
}

// The heights of a column inside a mesh (winding number > 0), as sorted
// disjoint intervals.
std::vector<std::pair<double, double>> InsideIntervals(std::vector<Crossing>& c) {
  std::sort(c.begin(), c.end(), [](const Crossing& a, const Crossing& b) { return a.z < b.z; });
  std::vector<std::pair<double, double>> out;
  int winding = 0;
  double start = 0;
  for (const Crossing& x : c) {
    const int before = winding;
    winding += x.step;
    if (before <= 0 && winding > 0) start = x.z;
    if (before > 0 && winding <= 0) out.emplace_back(start, x.z);
  }
  return out;
}

double Length(const std::vector<std::pair<double, double>>& s) {
  double l = 0;
  for (const auto& [lo, hi] : s) l += hi - lo;
  return l;
}

double OverlapLength(const std::vector<std::pair<double, double>>& a, const std::vector<std::pair<double, double>>& b) {
  double l = 0;
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    l += std::max(0.0, std::min(a[i].second, b[j].second) - std::max(a[i].first, b[j].first));
    if (a[i].second < b[j].second)
      ++i;
    else
      ++j;
  }
  return l;
}

}  // namespace

ColumnOverlap IntegrateColumnOverlap(const TriangleMesh& a, const TriangleMesh& b, double spacing) {
  if (!(spacing > 0) || !std::isfinite(spacing))
    throw InputError("column overlap: spacing must be a positive number of mm, got " + std::to_string(spacing));
  ColumnOverlap out;
  double lo_x = INFINITY, lo_y = INFINITY, hi_x = -INFINITY, hi_y = -INFINITY;
  for (const TriangleMesh* m : {&a, &b})
    for (const Vec3& v : m->vertices) {
      lo_x = std::min(lo_x, v[0]), hi_x = std::max(hi_x, v[0]);
      lo_y = std::min(lo_y, v[1]), hi_y = std::max(hi_y, v[1]);
    }
  if (!(lo_x <= hi_x && lo_y <= hi_y)) return out;
  // Column centres at cell centres shifted by an irrational fraction of a
  // cell (1/(2 + sqrt 2) and 1/(3 + pi)), away from round coordinates.
  Grid g;
  g.h = spacing;
  g.x0 = std::floor(lo_x / spacing) * spacing + spacing * (1.0 / (2.0 + std::sqrt(2.0)));
  g.y0 = std::floor(lo_y / spacing) * spacing + spacing * (1.0 / (3.0 + M_PI));
  g.nx = static_cast<long>(std::floor((hi_x - g.x0) / spacing)) + 1;
  g.ny = static_cast<long>(std::floor((hi_y - g.y0) / spacing)) + 1;
  if (g.nx <= 0 || g.ny <= 0) return out;
  if (static_cast<double>(g.nx) * static_cast<double>(g.ny) > 4e8)
    throw InputError("column overlap: " + std::to_string(g.nx) + " x " + std::to_string(g.ny) + " columns at spacing " +
                     std::to_string(spacing) + " mm is more than 4e8");
  const auto rows_a = TrianglesByRow(a, g), rows_b = TrianglesByRow(b, g);
  std::vector<std::vector<Crossing>> ca(static_cast<std::size_t>(g.nx)), cb(static_cast<std::size_t>(g.nx));
  double la = 0, lb = 0, lab = 0;
  for (long j = 0; j < g.ny; ++j) {
    const auto& ta = rows_a[static_cast<std::size_t>(j)];
    const auto& tb = rows_b[static_cast<std::size_t>(j)];
    if (ta.empty() && tb.empty()) continue;
    for (auto& c : ca) c.clear();
    for (auto& c : cb) c.clear();
    AddRowCrossings(a, ta, g, j, &ca);
    AddRowCrossings(b, tb, g, j, &cb);
    for (long i = 0; i < g.nx; ++i) {
      auto& xa = ca[static_cast<std::size_t>(i)];
      auto& xb = cb[static_cast<std::size_t>(i)];
      if (xa.empty() && xb.empty()) continue;
      ++out.columns;
      const auto ia = InsideIntervals(xa), ib = InsideIntervals(xb);
      la += Length(ia), lb += Length(ib), lab += OverlapLength(ia, ib);
    }
  }
  const double cell = spacing * spacing;
  out.volume_a = la * cell, out.volume_b = lb * cell, out.volume_both = lab * cell;
  return out;
}

}  // namespace fabatlas::mesh
