// The convex hull of points in the plane (see convex_hull_2d.h).
#include "convex_hull_2d.h"

#include <algorithm>

namespace fabatlas::design {

std::vector<Vec2> ConvexHull2D(std::vector<Vec2> pts) {
  std::sort(pts.begin(), pts.end());
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  if (pts.size() < 3) return pts;
  // > 0 when o, a, b turn counter-clockwise.
  auto cross = [](const Vec2& o, const Vec2& a, const Vec2& b) {
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
  };
  std::vector<Vec2> h(2 * pts.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {  // lower hull
    while (k >= 2 && cross(h[k - 2], h[k - 1], pts[i]) <= 0) --k;
    h[k++] = pts[i];
  }
  for (std::size_t i = pts.size() - 1, t = k + 1; i > 0; --i) {  // upper hull
    while (k >= t && cross(h[k - 2], h[k - 1], pts[i - 1]) <= 0) --k;
    h[k++] = pts[i - 1];
  }
  h.resize(k - 1);
  return h;
}

}  // namespace fabatlas::design
