// primitives.cc — level sets of primitives, extrusions, revolutions and
// meshes. Analytic shapes are sampled from exact signed distance functions,
// only in the narrow band: an octree descent skips every block whose centre
// is farther from the surface than the band plus the block's half diagonal
// (signed distance functions are 1-Lipschitz), so the cost grows with the
// surface area, not the bounding volume.
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <numbers>

#include "fabatlas/geometry/convex_mesh_distance.h"
#include "solid_impl.h"

namespace fabatlas::geometry {

using openvdb::Coord;
using openvdb::FloatGrid;
using openvdb::FloatTree;
using LeafT = FloatTree::LeafNodeType;

namespace {

using Sdf = std::function<double(double x, double y, double z)>;

constexpr int kTopBlock = 32;  // voxels per top-level block edge (4 leaves)

struct BandSampler {
  const Sdf& sdf;
  double vs;
  double band;  // world half width

  // The leaf at `o`'s cube of `size` voxels at local (x, y, z) into its
  // values and active mask, by the blocks' test: a cube whose centre lies
  // farther than the band plus its half diagonal is outside the band
  // throughout, on its centre's side (the values each voxel would give), so
  // it takes the band value unevaluated; otherwise its eight halves, down to
  // single voxels. Near thin walls most leaves straddle the band's edge:
  // this spares about half the distance evaluations.
  void Fill(const Coord& o, int x, int y, int z, int size, float* values,
            openvdb::util::NodeMask<LeafT::LOG2DIM>& on) const {
    const double half = 0.5 * (size - 1);
    const double d = sdf((o.x() + x + half) * vs, (o.y() + y + half) * vs, (o.z() + z + half) * vs);
    if (std::abs(d) > band + std::sqrt(3.0) * half * vs) {
      const float outside = static_cast<float>(d > 0 ? band : -band);
      for (int i = x; i < x + size; ++i)
        for (int j = y; j < y + size; ++j)
          for (int k = z; k < z + size; ++k) values[LeafT::coordToOffset(Coord(i, j, k))] = outside;
      return;
    }
    if (size > 2) {
      const int h = size / 2;
      for (int q = 0; q < 8; ++q)
        Fill(o, x + ((q & 1) ? h : 0), y + ((q & 2) ? h : 0), z + ((q & 4) ? h : 0), h, values, on);
      return;
    }
    for (int i = x; i < x + size; ++i)
      for (int j = y; j < y + size; ++j)
        for (int k = z; k < z + size; ++k) {
          const openvdb::Index n = LeafT::coordToOffset(Coord(i, j, k));
          const double v = sdf((o.x() + i) * vs, (o.y() + j) * vs, (o.z() + k) * vs);
          if (std::abs(v) < band) {
            values[n] = static_cast<float>(v);
            on.setOn(n);
          } else {
            values[n] = static_cast<float>(v > 0 ? band : -band);
          }
        }
  }

  // Visit the cube of `size` voxels per edge with minimum corner `o`.
  void Visit(const Coord& o, int size, std::vector<LeafT*>& out) const {
    const double half = 0.5 * (size - 1);
    const double d = sdf((o.x() + half) * vs, (o.y() + half) * vs, (o.z() + half) * vs);
    const double half_diag = std::sqrt(3.0) * half * vs;
    if (std::abs(d) > band + half_diag) return;
    if (size > static_cast<int>(LeafT::DIM)) {
      const int h = size / 2;
      for (int i = 0; i < 8; ++i) {
        Visit(o.offsetBy((i & 1) ? h : 0, (i & 2) ? h : 0, (i & 4) ? h : 0), h, out);
      }
      return;
    }
    auto* leaf = new LeafT(o, static_cast<float>(band), false);
    float* values = leaf->buffer().data();
    openvdb::util::NodeMask<LeafT::LOG2DIM> on;
    constexpr int h = LeafT::DIM / 2;  // the leaf itself passed the test above
    for (int q = 0; q < 8; ++q) Fill(o, (q & 1) ? h : 0, (q & 2) ? h : 0, (q & 4) ? h : 0, h, values, on);
    leaf->setValueMask(on);
    const bool any_active = !on.isOff();
    if (any_active) {
      out.push_back(leaf);
    } else {
      delete leaf;
    }
  }
};

inline int FloorDiv(int a, int b) { return (a >= 0) ? a / b : -((-a + b - 1) / b); }

// Narrow-band level set of `sdf` (exact signed distance, mm, negative inside)
// whose interior lies within [lo, hi].
// zero_sheets: remove the zero-thickness sheets of flush CSG faces
// (internal::RemoveZeroSheets) instead of only signing the inactive values.
Solid SampleSdf(const GridSpec& g, const Vec3& lo, const Vec3& hi, const Sdf& sdf, const char* what,
                bool zero_sheets = false) {
  internal::ValidateSpec(g, what);
  internal::EnsureOpenVdbInitialized();
  internal::CheckVoxelBudget(g, {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}, what);
  const double vs = g.voxel_size;
  const double band = g.half_width_voxels * vs;
  int ilo[3], ihi[3];
  for (int k = 0; k < 3; ++k) {
    ilo[k] = FloorDiv(static_cast<int>(std::floor((lo[k] - band) / vs)) - 1, kTopBlock);
    ihi[k] = FloorDiv(static_cast<int>(std::ceil((hi[k] + band) / vs)) + 1, kTopBlock);
  }
  std::vector<Coord> blocks;
  for (int i = ilo[0]; i <= ihi[0]; ++i)
    for (int j = ilo[1]; j <= ihi[1]; ++j)
      for (int k = ilo[2]; k <= ihi[2]; ++k) blocks.emplace_back(i * kTopBlock, j * kTopBlock, k * kTopBlock);

  BandSampler sampler{sdf, vs, band};
  // One slot per block, filled in parallel, merged in block order.
  std::vector<std::vector<LeafT*>> per_block(blocks.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, blocks.size()), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t b = r.begin(); b != r.end(); ++b) sampler.Visit(blocks[b], kTopBlock, per_block[b]);
  });
  FloatGrid::Ptr grid = FloatGrid::create(static_cast<float>(band));
  grid->setTransform(internal::CanonicalTransform(vs));
  FloatTree& tree = grid->tree();
  for (auto& leaves : per_block)
    for (LeafT* leaf : leaves) tree.addLeaf(leaf);
  if (zero_sheets)
    internal::RemoveZeroSheets(*grid, vs);
  else
    openvdb::tools::signedFloodFill(tree);
  return internal::MakeSolid(grid, g);
}

// ---- 2-D helpers -------------------------------------------------------------

// Signed distance from (px, py) to a simple closed polygon (either
// orientation), negative inside; crossing-number sign test.
double PolygonSdf(const std::vector<Vec2>& v, double px, double py) {
  double d = (px - v[0][0]) * (px - v[0][0]) + (py - v[0][1]) * (py - v[0][1]);
  double s = 1.0;
  const size_t n = v.size();
  for (size_t i = 0, j = n - 1; i < n; j = i, ++i) {
    const double ex = v[j][0] - v[i][0], ey = v[j][1] - v[i][1];
    const double wx = px - v[i][0], wy = py - v[i][1];
    const double t = std::clamp((wx * ex + wy * ey) / (ex * ex + ey * ey), 0.0, 1.0);
    const double bx = wx - ex * t, by = wy - ey * t;
    d = std::min(d, bx * bx + by * by);
    const bool c1 = py >= v[i][1], c2 = py<v[j][1], c3 = ex * wy> ey * wx;
    if ((c1 && c2 && c3) || (!c1 && !c2 && !c3)) s = -s;
  }
  return s * std::sqrt(d);
}

// Validated copy of a polygon: finite points, consecutive duplicates removed,
// at least three vertices and non-zero area.
std::vector<Vec2> CleanPolygon(const std::vector<Vec2>& in, const char* what) {
  std::vector<Vec2> out;
  for (size_t i = 0; i < in.size(); ++i) {
    if (!std::isfinite(in[i][0]) || !std::isfinite(in[i][1])) {
      char buf[200];
      std::snprintf(buf, sizeof buf, "%s: point %zu is not finite", what, i);
      throw InputError(buf);
    }
    if (out.empty() || out.back() != in[i]) out.push_back(in[i]);
  }
  while (out.size() > 1 && out.front() == out.back()) out.pop_back();
  double area2 = 0;
  for (size_t i = 0, j = out.size() - 1; i < out.size(); j = i, ++i)
    area2 += out[j][0] * out[i][1] - out[i][0] * out[j][1];
  if (out.size() < 3 || std::abs(area2) <= 0) {
    throw InputError(std::string(what) + ": polygon needs at least 3 distinct points and a non-zero area");
  }
  return out;
}

void PolygonBounds(const std::vector<Vec2>& p, Vec2& lo, Vec2& hi) {
  lo = hi = p[0];
  for (const Vec2& q : p)
    for (int k = 0; k < 2; ++k) {
      lo[k] = std::min(lo[k], q[k]);
      hi[k] = std::max(hi[k], q[k]);
    }
}

// Exact SDF of a box with half extents (hx, hy) in 2-D.
inline double Box2Sdf(double qx, double qy) {
  const double ox = std::max(qx, 0.0), oy = std::max(qy, 0.0);
  return std::sqrt(ox * ox + oy * oy) + std::min(std::max(qx, qy), 0.0);
}

// Smooth solid of revolution of a validated (r, z) profile.
Solid RevolveSmooth(const GridSpec& g, const std::vector<Vec2>& profile, const char* what) {
  Vec2 lo, hi;
  PolygonBounds(profile, lo, hi);
  const double R = hi[0];
  Sdf sdf = [&profile](double x, double y, double z) {
    // Exact: the nearest surface point lies in the meridian half-plane.
    return PolygonSdf(profile, std::hypot(x, y), z);
  };
  return SampleSdf(g, {-R, -R, lo[1]}, {R, R, hi[1]}, sdf, what);
}

// ---- Convex meshes --------------------------------------------------------------

}  // namespace

Solid FromDistance(const GridSpec& g, const Box3& bounds, const DistanceFunction& distance, const char* what) {
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(bounds.min[k]) || !std::isfinite(bounds.max[k]) || bounds.min[k] > bounds.max[k])
      throw InputError(std::string(what) + ": bounds are not a finite box");
  return SampleSdf(g, bounds.min, bounds.max, distance, what, /*zero_sheets=*/true);
}

// ---- Primitives ----------------------------------------------------------------

Solid Sphere(const GridSpec& g, double radius) {
  internal::RequirePositive(radius, "sphere", "radius");
  Sdf sdf = [radius](double x, double y, double z) { return std::sqrt(x * x + y * y + z * z) - radius; };
  return SampleSdf(g, {-radius, -radius, -radius}, {radius, radius, radius}, sdf, "sphere");
}

Solid Box(const GridSpec& g, const Vec3& size) {
  for (double s : size) internal::RequirePositive(s, "box", "edge length");
  const double hx = size[0] / 2, hy = size[1] / 2, hz = size[2] / 2;
  Sdf sdf = [=](double x, double y, double z) {
    const double qx = std::abs(x) - hx, qy = std::abs(y) - hy, qz = std::abs(z) - hz;
    const double ox = std::max(qx, 0.0), oy = std::max(qy, 0.0), oz = std::max(qz, 0.0);
    return std::sqrt(ox * ox + oy * oy + oz * oz) + std::min(std::max({qx, qy, qz}), 0.0);
  };
  return SampleSdf(g, {-hx, -hy, -hz}, {hx, hy, hz}, sdf, "box");
}

Solid Cylinder(const GridSpec& g, double radius, double height) {
  internal::RequirePositive(radius, "cylinder", "radius");
  internal::RequirePositive(height, "cylinder", "height");
  const double hz = height / 2;
  Sdf sdf = [=](double x, double y, double z) { return Box2Sdf(std::hypot(x, y) - radius, std::abs(z) - hz); };
  return SampleSdf(g, {-radius, -radius, -hz}, {radius, radius, hz}, sdf, "cylinder");
}

Solid Cone(const GridSpec& g, double bottom_radius, double top_radius, double height) {
  internal::RequirePositive(height, "cone", "height");
  if (!std::isfinite(bottom_radius) || !std::isfinite(top_radius) || bottom_radius < 0 || top_radius < 0 ||
      (bottom_radius == 0 && top_radius == 0)) {
    throw InputError("cone: radii must be finite, >= 0 and not both 0");
  }
  const double hz = height / 2;
  std::vector<Vec2> profile = CleanPolygon({{0, -hz}, {bottom_radius, -hz}, {top_radius, hz}, {0, hz}}, "cone");
  return RevolveSmooth(g, profile, "cone");
}

Solid Torus(const GridSpec& g, double major_radius, double minor_radius) {
  internal::RequirePositive(major_radius, "torus", "major radius");
  internal::RequirePositive(minor_radius, "torus", "minor radius");
  const double R = major_radius + minor_radius, r = minor_radius;
  Sdf sdf = [=](double x, double y, double z) { return std::hypot(std::hypot(x, y) - major_radius, z) - r; };
  return SampleSdf(g, {-R, -R, -r}, {R, R, r}, sdf, "torus");
}

Solid Capsule(const GridSpec& g, const Vec3& a, const Vec3& b, double radius) {
  internal::RequirePositive(radius, "capsule", "radius");
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(a[k]) || !std::isfinite(b[k])) throw InputError("capsule: end points must be finite");
  const double ex = b[0] - a[0], ey = b[1] - a[1], ez = b[2] - a[2];
  const double ee = ex * ex + ey * ey + ez * ez;
  Sdf sdf = [=](double x, double y, double z) {
    const double wx = x - a[0], wy = y - a[1], wz = z - a[2];
    const double t = ee > 0 ? std::clamp((wx * ex + wy * ey + wz * ez) / ee, 0.0, 1.0) : 0.0;
    const double dx = wx - t * ex, dy = wy - t * ey, dz = wz - t * ez;
    return std::sqrt(dx * dx + dy * dy + dz * dz) - radius;
  };
  Vec3 lo, hi;
  for (int k = 0; k < 3; ++k) {
    lo[k] = std::min(a[k], b[k]) - radius;
    hi[k] = std::max(a[k], b[k]) + radius;
  }
  return SampleSdf(g, lo, hi, sdf, "capsule");
}

Solid Extrude(const GridSpec& g, const std::vector<Vec2>& polygon, double height) {
  internal::RequirePositive(height, "extrude", "height");
  std::vector<Vec2> poly = CleanPolygon(polygon, "extrude");
  Vec2 lo, hi;
  PolygonBounds(poly, lo, hi);
  const double hz = height / 2;
  Sdf sdf = [poly = std::move(poly), hz](double x, double y, double z) {
    return Box2Sdf(PolygonSdf(poly, x, y), std::abs(z - hz) - hz);
  };
  return SampleSdf(g, {lo[0], lo[1], 0}, {hi[0], hi[1], height}, sdf, "extrude");
}

Solid Revolve(const GridSpec& g, const std::vector<Vec2>& profile_in, int sides) {
  std::vector<Vec2> profile = CleanPolygon(profile_in, "revolve");
  for (const Vec2& p : profile)
    if (p[0] < 0) throw InputError("revolve: profile radius r must be >= 0 at every point");
  if (sides == 0) return RevolveSmooth(g, profile, "revolve");
  if (sides < 3) throw InputError("revolve: sides must be 0 (smooth) or >= 3");
  internal::ValidateSpec(g, "revolve");
  internal::EnsureOpenVdbInitialized();
  // Faceted revolution: a closed triangle mesh whose cross-section at height z
  // is the regular n-gon with circumradius r(z) and a vertex on the +x axis;
  // meshToLevelSet turns it into a level set (it needs a closed surface, not
  // consistent orientation).
  Vec2 lo, hi;
  PolygonBounds(profile, lo, hi);
  internal::CheckVoxelBudget(g, {2 * hi[0], 2 * hi[0], hi[1] - lo[1]}, "revolve");
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> tris;
  std::vector<int> first(profile.size());  // first vertex of each ring
  std::vector<bool> on_axis(profile.size());
  for (size_t i = 0; i < profile.size(); ++i) {
    first[i] = static_cast<int>(points.size());
    on_axis[i] = profile[i][0] <= 0;
    if (on_axis[i]) {
      points.emplace_back(0.f, 0.f, static_cast<float>(profile[i][1]));
      continue;
    }
    for (int k = 0; k < sides; ++k) {
      const double phi = 2 * std::numbers::pi * k / sides;
      points.emplace_back(static_cast<float>(profile[i][0] * std::cos(phi)),
                          static_cast<float>(profile[i][0] * std::sin(phi)), static_cast<float>(profile[i][1]));
    }
  }
  auto vid = [&](size_t i, int k) -> openvdb::Index32 {
    return static_cast<openvdb::Index32>(on_axis[i] ? first[i] : first[i] + (k % sides));
  };
  for (size_t i = 0; i < profile.size(); ++i) {
    const size_t j = (i + 1) % profile.size();
    if (on_axis[i] && on_axis[j]) continue;  // degenerates to a segment of the axis
    for (int k = 0; k < sides; ++k) {
      if (!on_axis[i]) tris.emplace_back(vid(i, k), vid(i, k + 1), vid(j, k));
      if (!on_axis[j]) tris.emplace_back(vid(i, k + 1), vid(j, k + 1), vid(j, k));
    }
  }
  auto grid = openvdb::tools::meshToLevelSet<FloatGrid>(*internal::CanonicalTransform(g.voxel_size), points, tris,
                                                        static_cast<float>(g.half_width_voxels));
  return internal::MakeSolid(grid, g);
}

Solid FromMesh(const GridSpec& g, const mesh::TriangleMesh& m) {
  internal::ValidateSpec(g, "mesh");
  internal::EnsureOpenVdbInitialized();
  if (m.vertices.empty() || m.triangles.empty()) throw InputError("mesh: no triangles");
  Vec3 lo = m.vertices[0], hi = m.vertices[0];
  std::vector<openvdb::Vec3s> points;
  points.reserve(m.vertices.size());
  for (size_t i = 0; i < m.vertices.size(); ++i) {
    const auto& v = m.vertices[i];
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(v[k])) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "mesh: vertex %zu has a non-finite coordinate", i);
        throw InputError(buf);
      }
      lo[k] = std::min(lo[k], v[k]);
      hi[k] = std::max(hi[k], v[k]);
    }
    points.emplace_back(static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2]));
  }
  std::vector<openvdb::Vec3I> tris;
  tris.reserve(m.triangles.size());
  const auto nv = static_cast<std::int64_t>(m.vertices.size());
  for (size_t t = 0; t < m.triangles.size(); ++t) {
    const auto& tri = m.triangles[t];
    for (int k = 0; k < 3; ++k) {
      if (tri[k] < 0 || tri[k] >= nv) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "mesh: triangle %zu refers to vertex %d of %lld", t, tri[k],
                      static_cast<long long>(nv));
        throw InputError(buf);
      }
    }
    tris.emplace_back(tri[0], tri[1], tri[2]);
  }
  internal::CheckVoxelBudget(g, {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}, "mesh");
  // A closed convex mesh (OpenSCAD's cubes, cylinders, spheres and hulls):
  // its exact signed distance sampled in the band, 10-30x faster than
  // meshToLevelSet, whose cost grows with the triangles' area.
  if (Sdf sdf = ConvexMeshDistance(m, g.half_width_voxels * g.voxel_size)) {
    Solid s = SampleSdf(g, lo, hi, sdf, "mesh");
    if (s.empty()) throw InputError("mesh: no interior at this voxel size (open, flat or smaller than a voxel)");
    return s;
  }
  auto grid = openvdb::tools::meshToLevelSet<FloatGrid>(*internal::CanonicalTransform(g.voxel_size), points, tris,
                                                        static_cast<float>(g.half_width_voxels));
  Solid s = internal::MakeSolid(grid, g);
  if (s.empty()) throw InputError("mesh: no interior at this voxel size (open, flat or smaller than a voxel)");
  return s;
}

}  // namespace fabatlas::geometry
