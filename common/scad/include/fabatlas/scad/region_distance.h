// fabatlas/scad/region_distance.h — the signed distance to a region of the
// plane bounded by closed loops combined by the even-odd rule (OpenSCAD's
// polygon with paths, a text's glyph outlines): what a prism's exact signed
// distance is built from (docs/openscad.md, "Native evaluation").
#pragma once

#include <cstdint>
#include <vector>

#include "fabatlas/scad/primitive_mesh.h"

namespace fabatlas::scad {

class RegionDistance {
 public:
  // loops: closed polygons in mm (last point != first), any orientation; a
  // point is inside when it lies inside an odd number of them. Loops with
  // fewer than 3 points are ignored. Builds a uniform grid of edge buckets
  // (about one edge per cell, at most 256 x 256 cells): O(edges) memory.
  explicit RegionDistance(const std::vector<Loop>& loops);

  // Signed Euclidean distance from (x, y) to the loops' edges, negative
  // inside; exact (not a bound). +infinity for a region without edges.
  // Cost: the edges of the cells within the distance found (a ring search),
  // plus the edges of the point's row for the sign. Thread-safe (const).
  double operator()(double x, double y) const;

  bool empty() const { return edges_.empty(); }
  Point2 min() const { return lo_; }  // bounds of the loops' points
  Point2 max() const { return hi_; }

 private:
  struct Edge {
    Point2 a, b;
  };
  double Unsigned(double x, double y) const;
  bool Inside(double x, double y) const;

  std::vector<Edge> edges_;
  Point2 lo_{0, 0}, hi_{0, 0};
  double cell_ = 1;
  int nx_ = 0, ny_ = 0;
  std::vector<std::uint32_t> cell_start_, cell_edges_;  // CSR: edges overlapping each cell
  std::vector<std::uint32_t> row_start_, row_edges_;    // CSR: edges overlapping each row
};

}  // namespace fabatlas::scad
