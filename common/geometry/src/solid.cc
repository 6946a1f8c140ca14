// solid.cc — Solid: measures (volume, centre of mass, bounds) and the mesh
// road's lazy level set. Meshing is in solid_to_mesh.cc, the byte encoding
// in solid_bytes.cc, occupancy sampling in sample_occupancy.cc. See
// docs/geometry.md for the method notes.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <mutex>
#include <numbers>

#include "solid_impl.h"

namespace fabatlas::geometry {

using openvdb::FloatGrid;
using openvdb::FloatTree;
using LeafT = FloatTree::LeafNodeType;

namespace internal {

void EnsureOpenVdbInitialized() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

void RequirePositive(double value, const char* where, const char* name) {
  if (!std::isfinite(value) || value <= 0) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "%s: %s must be a finite number > 0 (got %g)", where, name, value);
    throw InputError(buf);
  }
}

void ValidateSpec(const GridSpec& spec, const char* where) {
  RequirePositive(spec.voxel_size, where, "voxel size");
  if (!std::isfinite(spec.half_width_voxels) || spec.half_width_voxels < 2.0) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "%s: narrow-band half width must be >= 2 voxels (got %g)", where,
                  spec.half_width_voxels);
    throw InputError(buf);
  }
}

openvdb::math::Transform::Ptr CanonicalTransform(double voxel_size) {
  return openvdb::math::Transform::createLinearTransform(voxel_size);
}

void CheckActiveVoxelEstimate(const GridSpec& spec, double estimated_active, const char* what) {
  if (!(estimated_active <= static_cast<double>(spec.max_active_voxels))) {
    char buf[320];
    std::snprintf(buf, sizeof buf, "voxel size %g mm on %s would need ~%.1e active voxels (limit %.1e)",
                  spec.voxel_size, what, estimated_active, static_cast<double>(spec.max_active_voxels));
    throw ResourceError(buf);
  }
}

void CheckVoxelBudget(const GridSpec& spec, const Vec3& extent, const char* what) {
  const double vs = spec.voxel_size;
  const double band = 2.0 * spec.half_width_voxels + 1.0;
  double e[3];
  for (int i = 0; i < 3; ++i) e[i] = extent[i] / vs + band;
  const double area = 2.0 * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0]);
  char desc[200];
  std::snprintf(desc, sizeof desc, "a %g x %g x %g mm %s", extent[0], extent[1], extent[2], what);
  CheckActiveVoxelEstimate(spec, area * band, desc);
}

Solid MakeSolid(FloatGrid::Ptr grid, const GridSpec& spec) {
  grid->setGridClass(openvdb::GRID_LEVEL_SET);
  grid->setName("solid");
  auto impl = std::make_shared<Solid::Impl>();
  impl->grid = std::move(grid);
  impl->spec = spec;
  return Solid(std::shared_ptr<const Solid::Impl>(std::move(impl)));
}

}  // namespace internal

namespace {

// Smooth Heaviside of the interior indicator, H(-phi), half width eps
// (Osher & Fedkiw, "Level Set Methods", eq. 1.23 style sine ramp):
// 0.5 (1 + x / eps + sin(pi x / eps) / pi) for x = -phi within eps of 0.
// `sine` is sin(pi x / eps), given by the caller.
inline double InsideWeight(double phi, double eps, double sine) {
  const double x = -phi;
  if (x <= -eps) return 0.0;
  if (x >= eps) return 1.0;
  return 0.5 * (1.0 + x / eps + sine / std::numbers::pi);
}

struct Moments {
  double m0 = 0;             // voxel count (weighted)
  double m1[3] = {0, 0, 0};  // first moments in index coordinates
  void Add(double w, const openvdb::Coord& c) {
    m0 += w;
    m1[0] += w * c.x();
    m1[1] += w * c.y();
    m1[2] += w * c.z();
  }
  void Add(const Moments& o) {
    m0 += o.m0;
    for (int k = 0; k < 3; ++k) m1[k] += o.m1[k];
  }
};

// Interior (negative) tiles above the leaf level, as index boxes: the root's
// tiles and the internal nodes' own. Node by node: the tree-level value
// iterator visits every tile slot through the whole tree's iterator stack
// (about 1.5 ms for the tray's grid, docs/benchmarks.md "OpenSCAD").
template <typename F>
void ForEachInteriorTile(const FloatTree& tree, F&& visit) {
  using Upper = FloatTree::RootNodeType::ChildNodeType;  // 4096 voxels a side
  using Lower = Upper::ChildNodeType;                    // 128 voxels a side
  for (auto it = tree.root().cbeginValueAll(); it; ++it)
    if (*it < 0) visit(openvdb::CoordBBox::createCube(it.getCoord(), Upper::DIM));
  std::vector<const Upper*> upper;
  tree.getNodes(upper);
  for (const Upper* node : upper)
    for (auto it = node->cbeginValueAll(); it; ++it)
      if (*it < 0) visit(openvdb::CoordBBox::createCube(it.getCoord(), Lower::DIM));
  std::vector<const Lower*> lower;
  tree.getNodes(lower);
  for (const Lower* node : lower)
    for (auto it = node->cbeginValueAll(); it; ++it)
      if (*it < 0) visit(openvdb::CoordBBox::createCube(it.getCoord(), LeafT::DIM));
}

// The measures of the interior, in one pass over the grid.
struct Measures {
  Moments moments;  // voxel units
  Box3 box;         // mm; all zero when nothing is inside
};

// One leaf's share of ComputeMeasures: the moments at both smoothing widths
// and the box of its inside voxels.
struct LeafMeasures {
  std::array<Moments, 2> m;
  static constexpr double inf = std::numeric_limits<double>::infinity();
  Box3 box{{inf, inf, inf}, {-inf, -inf, -inf}};
};

// What every leaf's measures read: the voxel size (mm), the distance beyond
// which a value is the background (mm), the two smoothing widths (mm) and
// whether the first is half the second.
struct Smoothing {
  double vs, deep, eps1, eps2;
  bool halves;
};

LeafMeasures MeasureLeaf(const LeafT& leaf, const Smoothing& w) {
  const double vs = w.vs, deep = w.deep, eps1 = w.eps1, eps2 = w.eps2;
  const bool halves = w.halves;
  LeafMeasures m;
  const float* values = leaf.buffer().data();
  const openvdb::Coord origin = leaf.origin();
  // Offset order of the leaf (x major, then y, then z), as its iterators.
  for (int x = 0, n = 0; x < 8; ++x)
    for (int y = 0; y < 8; ++y)
      for (int z = 0; z < 8; ++z, ++n) {
        const double phi = values[n];
        if (phi >= eps2) continue;
        const openvdb::Coord c = origin.offsetBy(x, y, z);
        // sin(pi x / eps2) and cos(pi x / eps2) once; sin(pi x / eps1)
        // = 2 sin cos when eps1 = eps2 / 2 (sin 2a = 2 sin a cos a).
        double sine2 = 0, sine1 = 0;
        if (phi > -eps2) {
          const double a = std::numbers::pi * -phi / eps2;
          const double s = std::sin(a);
          sine2 = s;
          if (std::abs(phi) < eps1) sine1 = halves ? 2 * s * std::cos(a) : std::sin(std::numbers::pi * -phi / eps1);
        }
        m.m[0].Add(InsideWeight(phi, eps1, sine1), c);
        m.m[1].Add(InsideWeight(phi, eps2, sine2), c);
        if (phi >= 0) continue;
        const double r = phi > -deep ? -phi : 0.0;
        const double p[3] = {c.x() * vs, c.y() * vs, c.z() * vs};
        for (int k = 0; k < 3; ++k) {
          m.box.min[k] = std::min(m.box.min[k], p[k] - r);
          m.box.max[k] = std::max(m.box.max[k], p[k] + r);
        }
      }
  return m;
}

// Zeroth and first moments of the interior indicator, in voxel units, and the
// interior's bounding box.
//
// Moments: the indicator is smoothed, H(-phi/eps), and summed over every
// voxel. The leading error of that sum is c * eps^2 * (total mean curvature of
// the surface, including sharp creases, where max/min CSG makes it large), so
// we sum with two smoothing widths, eps1 = 1 and eps2 = 2 voxels, in one pass
// and Richardson-extrapolate to eps = 0: M = (eps2^2 M(eps1) - eps1^2 M(eps2))
// / (eps2^2 - eps1^2). eps2 is capped by the narrow-band half width so every
// smoothed value comes from stored distances.
//
// Box: a voxel inside the solid at distance |phi| from the surface: the
// surface reaches at least |phi| beyond it along every axis direction it
// faces, and the extreme voxel along an axis gives the extent to within
// interpolation accuracy; an interior tile counts whole.
//
// Leaves are processed in parallel into per-leaf slots and summed in a fixed
// order, so results are bit-identical whatever the thread count.
Measures ComputeMeasures(const FloatGrid& grid, double half_width_voxels) {
  const FloatTree& tree = grid.tree();
  const double vs = grid.voxelSize()[0];
  const double deep = 0.99 * grid.background();
  const double e1 = 1.0, e2 = std::min(2.0, half_width_voxels);  // voxels
  const double eps1 = e1 * vs, eps2 = e2 * vs;                   // mm
  const bool halves = e2 == 2 * e1;                              // one sin and cos serve both widths
  const Smoothing widths{vs, deep, eps1, eps2, halves};
  constexpr double inf = std::numeric_limits<double>::infinity();
  std::vector<const LeafT*> leaves;
  tree.getNodes(leaves);
  std::vector<LeafMeasures> per_leaf(leaves.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.size()), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) per_leaf[i] = MeasureLeaf(*leaves[i], widths);
  });
  std::array<Moments, 2> sum;
  Box3 box{{inf, inf, inf}, {-inf, -inf, -inf}};
  auto grow = [&box](const Box3& b) {
    for (int k = 0; k < 3; ++k) {
      box.min[k] = std::min(box.min[k], b.min[k]);
      box.max[k] = std::max(box.max[k], b.max[k]);
    }
  };
  for (const auto& m : per_leaf) {
    sum[0].Add(m.m[0]);
    sum[1].Add(m.m[1]);
    grow(m.box);
  }
  const double a = e2 * e2 / (e2 * e2 - e1 * e1), b = -e1 * e1 / (e2 * e2 - e1 * e1);
  Measures out;
  Moments& total = out.moments;
  total.m0 = a * sum[0].m0 + b * sum[1].m0;
  for (int k = 0; k < 3; ++k) total.m1[k] = a * sum[0].m1[k] + b * sum[1].m1[k];
  if (total.m0 < 0) total = Moments{};
  // Interior tiles (inactive, negative) above the leaf level count fully.
  ForEachInteriorTile(tree, [&](const openvdb::CoordBBox& bb) {
    const double n = static_cast<double>(bb.volume());
    total.m0 += n;
    total.m1[0] += n * 0.5 * (bb.min().x() + bb.max().x());
    total.m1[1] += n * 0.5 * (bb.min().y() + bb.max().y());
    total.m1[2] += n * 0.5 * (bb.min().z() + bb.max().z());
    grow({{bb.min().x() * vs, bb.min().y() * vs, bb.min().z() * vs},
          {bb.max().x() * vs, bb.max().y() * vs, bb.max().z() * vs}});
  });
  if (box.min[0] <= box.max[0]) out.box = box;
  return out;
}

}  // namespace

const FloatGrid::Ptr& Solid::Impl::Grid() const {
  if (boundary) {
    std::call_once(grid_once, [this] {
      grid = boundary->triangles.empty()
                 ? FloatGrid::create(static_cast<float>(spec.half_width_voxels * spec.voxel_size))
                 : FromMesh(spec, *boundary).impl()->Grid();
      if (boundary->triangles.empty()) {
        grid->setTransform(internal::CanonicalTransform(spec.voxel_size));
        grid->setGridClass(openvdb::GRID_LEVEL_SET);
        grid->setName("solid");
      }
    });
  }
  return grid;
}

Solid MeshSolid(const GridSpec& g, mesh::TriangleMesh boundary) {
  internal::ValidateSpec(g, "MeshSolid");
  for (const auto& v : boundary.vertices)
    if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]))
      throw InputError("MeshSolid: a vertex coordinate is not a finite number");
  for (const auto& t : boundary.triangles)
    for (std::int32_t i : t)
      if (i < 0 || static_cast<std::size_t>(i) >= boundary.vertices.size())
        throw InputError("MeshSolid: a triangle refers to a missing vertex");
  if (boundary.triangles.empty()) return Solid();
  auto impl = std::make_shared<Solid::Impl>();
  impl->spec = g;
  impl->boundary = std::make_shared<const mesh::TriangleMesh>(std::move(boundary));
  return Solid(std::shared_ptr<const Solid::Impl>(std::move(impl)));
}

Solid::Solid() = default;
Solid::Solid(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}

const mesh::TriangleMesh* Solid::boundary() const { return impl_ ? impl_->boundary.get() : nullptr; }

bool Solid::empty() const {
  if (!impl_) return true;
  if (impl_->boundary) return impl_->boundary->triangles.empty();
  const FloatTree& tree = impl_->Grid()->tree();
  // The band's leaves first: a solid with material has negative voxels there.
  std::vector<const LeafT*> leaves;
  tree.getNodes(leaves);
  for (const LeafT* leaf : leaves) {
    const float* values = leaf->buffer().data();
    for (openvdb::Index n = 0; n < LeafT::SIZE; ++n)
      if (values[n] < 0) return false;
  }
  bool inside = false;
  ForEachInteriorTile(tree, [&inside](const openvdb::CoordBBox&) { inside = true; });
  return !inside;
}

double Solid::voxel_size() const { return impl_ ? impl_->spec.voxel_size : 0.0; }

namespace {
// The solid's measures, computed on first use and kept with its grid.
const Solid::Impl& WithMeasures(const Solid::Impl& impl) {
  std::call_once(impl.measures_once, [&impl] {
    if (impl.boundary) {  // the mesh's own: divergence theorem over its triangles
      const mesh::TriangleMesh& b = *impl.boundary;
      double six = 0, c[3] = {0, 0, 0};
      Box3 box{{b.vertices[0][0], b.vertices[0][1], b.vertices[0][2]},
               {b.vertices[0][0], b.vertices[0][1], b.vertices[0][2]}};
      for (const auto& v : b.vertices)
        for (int k = 0; k < 3; ++k) {
          box.min[k] = std::min(box.min[k], v[k]);
          box.max[k] = std::max(box.max[k], v[k]);
        }
      for (const auto& t : b.triangles) {
        const auto& p = b.vertices[t[0]];
        const auto& q = b.vertices[t[1]];
        const auto& r = b.vertices[t[2]];
        const double d = p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) +
                         p[2] * (q[0] * r[1] - q[1] * r[0]);
        six += d;
        for (int k = 0; k < 3; ++k) c[k] += d * (p[k] + q[k] + r[k]);
      }
      const double vs = impl.spec.voxel_size, v = six / 6;
      // In voxel units, as the level set's: m0 = V / vs^3, m1 = V c / vs^4 (c = sum / (4 * six)).
      impl.moments = {v / (vs * vs * vs), c[0] / 24 / (vs * vs * vs * vs), c[1] / 24 / (vs * vs * vs * vs),
                      c[2] / 24 / (vs * vs * vs * vs)};
      impl.box = box;
      return;
    }
    const Measures m = ComputeMeasures(*impl.Grid(), impl.spec.half_width_voxels);
    impl.moments = {m.moments.m0, m.moments.m1[0], m.moments.m1[1], m.moments.m1[2]};
    impl.box = m.box;
  });
  return impl;
}
}  // namespace

double Solid::Volume() const {
  if (!impl_) return 0.0;
  const double vs = impl_->spec.voxel_size;
  return WithMeasures(*impl_).moments[0] * vs * vs * vs;
}

Vec3 Solid::CenterOfMass() const {
  if (!impl_) return {0, 0, 0};
  const std::array<double, 4>& m = WithMeasures(*impl_).moments;
  if (m[0] <= 0) return {0, 0, 0};
  const double vs = impl_->spec.voxel_size;
  return {m[1] / m[0] * vs, m[2] / m[0] * vs, m[3] / m[0] * vs};
}

Box3 Solid::BoundingBox() const {
  if (!impl_) return {};
  return WithMeasures(*impl_).box;
}

std::size_t Solid::MemoryBytes() const {
  if (!impl_) return 0;
  // A mesh solid counts its mesh only, so the figure does not depend on
  // whether some operation voxelised it yet.
  if (impl_->boundary)
    return sizeof(mesh::TriangleMesh) + impl_->boundary->vertices.size() * sizeof(impl_->boundary->vertices[0]) +
           impl_->boundary->triangles.size() * sizeof(impl_->boundary->triangles[0]);
  return static_cast<std::size_t>(impl_->Grid()->memUsage());
}

}  // namespace fabatlas::geometry
