// Swept-volume signed distance on a sparse OpenVDB grid with narrow-band
// culling (Reconfigurables, section 6.7, Eq. 5), and its epsilon-offset surface.
#include "fabatlas/swept/swept_volume.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>

#include "fabatlas/error.h"

namespace fabatlas::swept {

struct SweptDistanceField::Impl {
  openvdb::FloatGrid::Ptr grid;  // level set, background = band half width
  double voxel_size = 0;
  double band = 0;
};

namespace {

using openvdb::Coord;
using openvdb::FloatGrid;
using openvdb::MaskGrid;

void CheckOptions(const SweptVolumeOptions& o) {
  if (!(o.voxel_size > 0) || !std::isfinite(o.voxel_size)) throw InputError("swept volume: voxel_size must be > 0");
  if (!(o.offset >= 0) || !std::isfinite(o.offset)) throw InputError("swept volume: offset must be >= 0");
  if (o.time_steps < 2) throw InputError("swept volume: time_steps must be >= 2");
  if (!(o.max_step_displacement >= 0) || !std::isfinite(o.max_step_displacement)) {
    throw InputError("swept volume: max_step_displacement must be >= 0");
  }
  if (!(o.half_width_voxels >= 2) || !std::isfinite(o.half_width_voxels)) {
    throw InputError("swept volume: half_width_voxels must be >= 2");
  }
}

// Bounding box corners of the mesh; throws on empty / non-finite / bad indices.
std::array<Vec3, 8> CheckedCorners(const mesh::TriangleMesh& m) {
  if (m.vertices.empty() || m.triangles.empty()) throw InputError("swept volume: body mesh has no triangles");
  Vec3 lo = m.vertices[0], hi = m.vertices[0];
  for (std::size_t i = 0; i < m.vertices.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(m.vertices[i][k])) {
        throw InputError("swept volume: body vertex " + std::to_string(i) + " has a non-finite coordinate");
      }
      lo[k] = std::min(lo[k], m.vertices[i][k]);
      hi[k] = std::max(hi[k], m.vertices[i][k]);
    }
  }
  const auto nv = static_cast<std::int64_t>(m.vertices.size());
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      if (m.triangles[t][k] < 0 || m.triangles[t][k] >= nv) {
        throw InputError("swept volume: body triangle " + std::to_string(t) + " refers to a missing vertex");
      }
    }
  }
  std::array<Vec3, 8> c;
  for (int i = 0; i < 8; ++i) c[i] = {(i & 1) ? hi[0] : lo[0], (i & 2) ? hi[1] : lo[1], (i & 4) ? hi[2] : lo[2]};
  return c;
}

// Hausdorff bound between two poses of the body: the largest displacement of
// a bounding-box corner (displacement is affine in x, so its norm is maximal
// at a vertex of the box).
double PoseDistance(const std::array<Vec3, 8>& corners, const Transform& a, const Transform& b) {
  double m = 0;
  for (const auto& c : corners) {
    const Vec3 pa = a.Apply(c), pb = b.Apply(c);
    m = std::max(m, std::hypot(pa[0] - pb[0], pa[1] - pb[1], pa[2] - pb[2]));
  }
  return m;
}

openvdb::math::Transform::Ptr Lattice(double h) { return openvdb::math::Transform::createLinearTransform(h); }

}  // namespace

// ---- SweptDistanceField ------------------------------------------------------

SweptDistanceField::SweptDistanceField() = default;
SweptDistanceField::SweptDistanceField(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}
double SweptDistanceField::voxel_size() const { return impl_ ? impl_->voxel_size : 0.0; }
double SweptDistanceField::band_half_width() const { return impl_ ? impl_->band : 0.0; }
std::size_t SweptDistanceField::active_voxels() const {
  return impl_ ? static_cast<std::size_t>(impl_->grid->activeVoxelCount()) : 0;
}

double SweptDistanceField::Value(const Vec3& p) const {
  if (!impl_) return 0.0;
  const double h = impl_->voxel_size;
  auto acc = impl_->grid->getConstAccessor();
  return openvdb::tools::BoxSampler::sample(acc, openvdb::Vec3R(p[0] / h, p[1] / h, p[2] / h));
}

double SweptDistanceField::ValueAtVoxel(const std::array<int, 3>& ijk) const {
  if (!impl_) return 0.0;
  return impl_->grid->tree().getValue(Coord(ijk[0], ijk[1], ijk[2]));
}

std::vector<SweptDistanceField::Voxel> SweptDistanceField::ActiveVoxels() const {
  std::vector<Voxel> out;
  if (!impl_) return out;
  out.reserve(impl_->grid->activeVoxelCount());
  for (auto it = impl_->grid->cbeginValueOn(); it; ++it) {
    const Coord c = it.getCoord();
    out.push_back({{c.x(), c.y(), c.z()}, *it});
  }
  return out;
}

mesh::TriangleMesh SweptDistanceField::Surface(double iso) const {
  mesh::TriangleMesh out;
  if (!impl_) return out;
  if (!(std::abs(iso) < impl_->band - impl_->voxel_size)) {
    throw InputError("swept volume: iso value " + std::to_string(iso) + " mm lies outside the narrow band");
  }
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> tris;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(*impl_->grid, points, tris, quads, iso, 0.0);
  out.vertices.reserve(points.size());
  for (const auto& p : points) out.vertices.push_back({p.x(), p.y(), p.z()});
  // volumeToMesh emits clockwise polygons (seen from outside) for a level set;
  // reverse them to the outward convention of TriangleMesh.
  auto idx = [](openvdb::Index32 i) { return static_cast<std::int32_t>(i); };
  out.triangles.reserve(tris.size() + 2 * quads.size());
  for (const auto& q : quads) {
    out.triangles.push_back({idx(q[0]), idx(q[2]), idx(q[1])});
    out.triangles.push_back({idx(q[0]), idx(q[3]), idx(q[2])});
  }
  for (const auto& t : tris) out.triangles.push_back({idx(t[0]), idx(t[2]), idx(t[1])});
  return out;
}

// ---- Computation -------------------------------------------------------------

std::vector<Transform> SampleMotion(const mesh::TriangleMesh& body, const RigidMotion& motion,
                                    const SweptVolumeOptions& options) {
  return SamplePoses(
      body, [&motion](double t) { return motion.At(t); }, options);
}

std::vector<Transform> SamplePoses(const mesh::TriangleMesh& body, const std::function<Transform(double)>& motion,
                                   const SweptVolumeOptions& options) {
  CheckOptions(options);
  const auto corners = CheckedCorners(body);
  const double max_step = options.max_step_displacement > 0 ? options.max_step_displacement : options.voxel_size;
  // Path length bound of the fastest point, from a fine sampling of the motion.
  constexpr int kProbe = 4096;
  double path = 0;
  Transform prev = motion(0.0);
  for (int i = 1; i <= kProbe; ++i) {
    const Transform cur = motion(static_cast<double>(i) / kProbe);
    path += PoseDistance(corners, prev, cur);
    prev = cur;
  }
  const double wanted = std::ceil(path / max_step) + 1;
  if (wanted > 1e6) throw ResourceError("swept volume: motion would need more than 1e6 time steps at this resolution");
  const int steps = std::max(options.time_steps, static_cast<int>(wanted));
  std::vector<Transform> poses;
  poses.reserve(steps);
  for (int i = 0; i < steps; ++i) poses.push_back(motion(static_cast<double>(i) / (steps - 1)));
  return poses;
}

namespace {

// The body's level set on `lattice` (voxel size h, mm), wide enough that
// every body voxel within w + h of the surface carries a true distance.
FloatGrid::Ptr BodyLevelSet(const mesh::TriangleMesh& body, const openvdb::math::Transform& lattice, double w,
                            double h) {
  std::vector<openvdb::Vec3s> points;
  points.reserve(body.vertices.size());
  for (const auto& v : body.vertices) points.emplace_back(float(v[0]), float(v[1]), float(v[2]));
  std::vector<openvdb::Vec3I> tris;
  tris.reserve(body.triangles.size());
  for (const auto& t : body.triangles) tris.emplace_back(t[0], t[1], t[2]);
  FloatGrid::Ptr body_sdf =
      openvdb::tools::meshToLevelSet<FloatGrid>(lattice, points, tris, static_cast<float>(w / h + 2.0));
  if (body_sdf->activeVoxelCount() == 0) throw InputError("swept volume: body mesh encloses no voxel");
  return body_sdf;
}

// Touched world voxels of one pose f: the body's band centres `band` under
// f, rounded to the lattice (voxel size h), then dilated by one voxel in the
// 26-neighbourhood (covers every lattice point within one voxel per axis of
// a mapped band centre). In parallel over the band; the union is the same
// for any schedule.
MaskGrid::Ptr TouchedVoxels(const std::vector<Vec3>& band, const Transform& f, double h) {
  tbb::combinable<MaskGrid::Ptr> local([] { return MaskGrid::create(false); });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, band.size(), 4096), [&](const auto& r) {
    auto& mask = local.local();
    auto acc = mask->getAccessor();
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const Vec3 p = f.Apply(band[i]);
      acc.setValueOn(Coord(static_cast<int>(std::lround(p[0] / h)), static_cast<int>(std::lround(p[1] / h)),
                           static_cast<int>(std::lround(p[2] / h))));
    }
  });
  MaskGrid::Ptr touched = MaskGrid::create(false);
  local.combine_each([&](const MaskGrid::Ptr& m) { touched->tree().topologyUnion(m->tree()); });
  openvdb::tools::dilateActiveValues(touched->tree(), 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                     openvdb::tools::IGNORE_TILES);
  touched->tree().voxelizeActiveTiles();
  return touched;
}

// Each touched voxel of `result` takes min(current, d_B(g p)), clamped below
// at -w (g: world to body frame). Leaves of the mask and the result share
// origins, so each leaf is one thread's. Returns the voxels updated.
std::uint64_t LowerToBodyDistance(const MaskGrid& touched, const FloatGrid& body_sdf, const Transform& g, double h,
                                  double w, FloatGrid& result) {
  std::atomic<std::uint64_t> updates{0};
  openvdb::tree::LeafManager<const openvdb::MaskTree> leaves(touched.tree());
  tbb::parallel_for(leaves.leafRange(), [&](const auto& range) {
    auto acc = body_sdf.getConstAccessor();
    std::uint64_t n = 0;
    for (auto leaf = range.begin(); leaf; ++leaf) {
      auto* out = result.tree().probeLeaf(leaf->origin());
      if (out == nullptr) continue;  // cannot happen after topologyUnion
      for (auto v = leaf->cbeginValueOn(); v; ++v) {
        const Coord c = v.getCoord();
        const Vec3 q = g.Apply({c.x() * h, c.y() * h, c.z() * h});
        const float d =
            static_cast<float>(openvdb::tools::BoxSampler::sample(acc, openvdb::Vec3R(q[0] / h, q[1] / h, q[2] / h)));
        const float cur = out->getValue(v.pos());
        if (d < cur) out->setValueOnly(v.pos(), std::max(d, static_cast<float>(-w)));
        ++n;
      }
    }
    updates += n;
  });
  return updates.load();
}

}  // namespace

SweptDistanceField ComputeSweptDistance(const mesh::TriangleMesh& body, const std::vector<Transform>& poses,
                                        const SweptVolumeOptions& options, SweptVolumeSummary* summary) {
  CheckOptions(options);
  const auto corners = CheckedCorners(body);
  if (poses.empty()) throw InputError("swept volume: no poses");
  openvdb::initialize();
  const double h = options.voxel_size;

  // Band half width w: the requested width, the offset plus two voxels, and
  // the largest displacement between consecutive poses plus two voxels (the
  // continuity argument in the header).
  double step = 0;
  for (std::size_t i = 1; i < poses.size(); ++i) step = std::max(step, PoseDistance(corners, poses[i - 1], poses[i]));
  const double w = std::max({options.half_width_voxels * h, options.offset + 2 * h, step + 2 * h});

  // B's level set, once.
  const auto lattice = Lattice(h);
  FloatGrid::Ptr body_sdf = BodyLevelSet(body, *lattice, w, h);

  // Centres (mm, body frame) of B's band voxels with |d| < w + h.
  std::vector<Vec3> band;
  for (auto it = body_sdf->cbeginValueOn(); it; ++it) {
    if (std::abs(*it) < w + h) {
      const Coord c = it.getCoord();
      band.push_back({c.x() * h, c.y() * h, c.z() * h});
    }
  }

  FloatGrid::Ptr result = FloatGrid::create(static_cast<float>(w));
  result->setTransform(lattice->copy());
  result->setGridClass(openvdb::GRID_LEVEL_SET);
  std::uint64_t updates = 0;
  for (const Transform& f : poses) {
    const Transform g = f.Inverse();
    // 1. Touched world voxels.
    MaskGrid::Ptr touched = TouchedVoxels(band, f, h);
    result->tree().topologyUnion(touched->tree());
    if (static_cast<std::size_t>(result->tree().activeLeafVoxelCount()) > options.max_active_voxels) {
      throw ResourceError("swept volume: more than " + std::to_string(options.max_active_voxels) +
                          " active voxels; use a larger voxel_size");
    }
    // 2. Each touched voxel takes min(current, d_B(f^-1 p)).
    updates += LowerToBodyDistance(*touched, *body_sdf, g, h, w, *result);
  }
  // Inactive voxels inside the swept volume get -w (sign from the band).
  openvdb::tools::signedFloodFill(result->tree());

  if (summary != nullptr) {
    summary->time_steps = static_cast<int>(poses.size());
    summary->band_half_width = w;
    summary->body_band_voxels = band.size();
    summary->voxel_updates = updates;
    summary->active_voxels = static_cast<std::size_t>(result->activeVoxelCount());
  }
  auto impl = std::make_shared<SweptDistanceField::Impl>();
  impl->grid = result;
  impl->voxel_size = h;
  impl->band = w;
  return SweptDistanceField(std::move(impl));
}

SweptDistanceField ComputeSweptDistance(const mesh::TriangleMesh& body, const RigidMotion& motion,
                                        const SweptVolumeOptions& options, SweptVolumeSummary* summary) {
  return ComputeSweptDistance(body, SampleMotion(body, motion, options), options, summary);
}

SweptDistanceField ComputeSweptDistance(const geometry::Solid& body, const RigidMotion& motion,
                                        const SweptVolumeOptions& options, SweptVolumeSummary* summary) {
  if (body.empty()) throw InputError("swept volume: body solid is empty");
  return ComputeSweptDistance(body.ToMesh(), motion, options, summary);
}

mesh::TriangleMesh SweptOffsetSurface(const mesh::TriangleMesh& body, const RigidMotion& motion,
                                      const SweptVolumeOptions& options) {
  return ComputeSweptDistance(body, motion, options).Surface(options.offset);
}

geometry::Solid SweptOffsetSolid(const geometry::GridSpec& g, const mesh::TriangleMesh& body, const RigidMotion& motion,
                                 const SweptVolumeOptions& options) {
  return geometry::FromMesh(g, SweptOffsetSurface(body, motion, options));
}

}  // namespace fabatlas::swept
