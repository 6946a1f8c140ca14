// Signed distance to an even-odd region of loops (fabatlas/scad/region_distance.h).
#include "fabatlas/scad/region_distance.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace fabatlas::scad {
namespace {

double SegmentDistance2(double px, double py, const Point2& a, const Point2& b) {
  const double ex = b[0] - a[0], ey = b[1] - a[1];
  const double wx = px - a[0], wy = py - a[1];
  const double ee = ex * ex + ey * ey;
  const double t = ee > 0 ? std::clamp((wx * ex + wy * ey) / ee, 0.0, 1.0) : 0.0;
  const double dx = wx - t * ex, dy = wy - t * ey;
  return dx * dx + dy * dy;
}

// Compressed rows: bucket b holds items[start[b] .. start[b + 1]).
void Compress(const std::vector<std::vector<std::uint32_t>>& buckets, std::vector<std::uint32_t>& start,
              std::vector<std::uint32_t>& items) {
  start.assign(buckets.size() + 1, 0);
  for (std::size_t b = 0; b < buckets.size(); ++b)
    start[b + 1] = start[b] + static_cast<std::uint32_t>(buckets[b].size());
  items.clear();
  items.reserve(start.back());
  for (const auto& b : buckets) items.insert(items.end(), b.begin(), b.end());
}

}  // namespace

RegionDistance::RegionDistance(const std::vector<Loop>& loops) {
  bool first = true;
  for (const Loop& l : loops) {
    if (l.size() < 3) continue;
    for (std::size_t i = 0; i < l.size(); ++i) {
      const Point2& a = l[i];
      const Point2& b = l[(i + 1) % l.size()];
      if (a == b) continue;
      edges_.push_back({a, b});
      for (int k = 0; k < 2; ++k) {
        lo_[k] = first ? a[k] : std::min(lo_[k], a[k]);
        hi_[k] = first ? a[k] : std::max(hi_[k], a[k]);
      }
      first = false;
    }
  }
  if (edges_.empty()) return;
  const double w = std::max(hi_[0] - lo_[0], 1e-9), h = std::max(hi_[1] - lo_[1], 1e-9);
  // About one edge per cell, at most 256 cells along an axis.
  cell_ = std::max({std::sqrt(w * h / static_cast<double>(edges_.size())), w / 256, h / 256});
  nx_ = std::max(1, static_cast<int>(std::ceil(w / cell_)));
  ny_ = std::max(1, static_cast<int>(std::ceil(h / cell_)));
  std::vector<std::vector<std::uint32_t>> cells(static_cast<std::size_t>(nx_) * ny_), rows(ny_);
  auto clampi = [](double v, int n) { return std::clamp(static_cast<int>(std::floor(v)), 0, n - 1); };
  for (std::uint32_t e = 0; e < edges_.size(); ++e) {
    const Edge& E = edges_[e];
    const int i0 = clampi((std::min(E.a[0], E.b[0]) - lo_[0]) / cell_, nx_);
    const int i1 = clampi((std::max(E.a[0], E.b[0]) - lo_[0]) / cell_, nx_);
    const int j0 = clampi((std::min(E.a[1], E.b[1]) - lo_[1]) / cell_, ny_);
    const int j1 = clampi((std::max(E.a[1], E.b[1]) - lo_[1]) / cell_, ny_);
    for (int j = j0; j <= j1; ++j) {
      rows[j].push_back(e);
      for (int i = i0; i <= i1; ++i) cells[static_cast<std::size_t>(j) * nx_ + i].push_back(e);
    }
  }
  Compress(cells, cell_start_, cell_edges_);
  Compress(rows, row_start_, row_edges_);
}

bool RegionDistance::Inside(double x, double y) const {
  if (y < lo_[1] || y > hi_[1]) return false;
  const int j = std::clamp(static_cast<int>(std::floor((y - lo_[1]) / cell_)), 0, ny_ - 1);
  bool inside = false;
  for (std::uint32_t k = row_start_[j]; k < row_start_[j + 1]; ++k) {
    const Edge& e = edges_[row_edges_[k]];
    if ((e.a[1] > y) != (e.b[1] > y) && x < (e.b[0] - e.a[0]) * (y - e.a[1]) / (e.b[1] - e.a[1]) + e.a[0])
      inside = !inside;
  }
  return inside;
}

double RegionDistance::Unsigned(double x, double y) const {
  // The point's cell, clamped into the grid; after scanning the rings of
  // cells up to k around it, every other edge is at least k cells away.
  const int ci = std::clamp(static_cast<int>(std::floor((x - lo_[0]) / cell_)), 0, nx_ - 1);
  const int cj = std::clamp(static_cast<int>(std::floor((y - lo_[1]) / cell_)), 0, ny_ - 1);
  double best2 = std::numeric_limits<double>::infinity();
  const int rings = std::max({ci, nx_ - 1 - ci, cj, ny_ - 1 - cj});
  auto scan = [&](int i, int j) {
    if (i < 0 || j < 0 || i >= nx_ || j >= ny_) return;
    const std::size_t c = static_cast<std::size_t>(j) * nx_ + i;
    for (std::uint32_t k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
      const Edge& e = edges_[cell_edges_[k]];
      best2 = std::min(best2, SegmentDistance2(x, y, e.a, e.b));
    }
  };
  for (int k = 0; k <= rings; ++k) {
    if (k == 0) {
      scan(ci, cj);
    } else {
      for (int i = ci - k; i <= ci + k; ++i) {
        scan(i, cj - k);
        scan(i, cj + k);
      }
      for (int j = cj - k + 1; j <= cj + k - 1; ++j) {
        scan(ci - k, j);
        scan(ci + k, j);
      }
    }
    const double reach = k * cell_;
    if (best2 <= reach * reach) break;
  }
  return std::sqrt(best2);
}

double RegionDistance::operator()(double x, double y) const {
  if (edges_.empty()) return std::numeric_limits<double>::infinity();
  const double d = Unsigned(x, y);
  return Inside(x, y) ? -d : d;
}

}  // namespace fabatlas::scad
