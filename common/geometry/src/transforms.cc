// transforms.cc — Translate, Rotate and Scale of solids: a mesh solid's
// vertices mapped, a level set shifted by whole voxels or resampled.
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/SignedFloodFill.h>

#include <array>
#include <cmath>
#include <numbers>
#include <utility>
#include <vector>

#include "narrow_band.h"
#include "solid_impl.h"

namespace fabatlas::geometry {

using openvdb::FloatGrid;

namespace {

using internal::ActiveVoxels;
using internal::AssembleNarrowBand;
using internal::EmptyGrid;
using internal::Rebuild;

// Resample s after mapping its geometry by `post` (applied after s's
// canonical index-to-world map). For rigid maps and enlargements the signed
// distances themselves are interpolated (triquadratic) at the new voxel
// centres, which keeps sharp edges and curvature; shrinking maps would thin
// the narrow band, so they rebuild from the mesh of the zero level set.
template <typename Fn>
Solid MapAndRebuild(const Solid& s, Fn post, double scale = 1.0) {
  const GridSpec& spec = s.impl()->spec;
  const FloatGrid& in = *s.impl()->Grid();
  auto xform = in.transform().copy();
  post(*xform);
  if (scale < 1.0) {
    // A new grid object sharing the (unmodified) tree, with its own transform.
    FloatGrid::Ptr src = openvdb::ConstPtrCast<FloatGrid>(in.copy());
    src->setTransform(xform);
    return Rebuild(*src, spec);
  }
  const auto out_xform = internal::CanonicalTransform(spec.voxel_size);
  const double bg = spec.half_width_voxels * spec.voxel_size;
  // Candidate output voxels: the images of the input's active voxels,
  // dilated to close the gaps a rotation or enlargement leaves.
  openvdb::MaskGrid::Ptr mask = openvdb::MaskGrid::create(false);
  {
    auto macc = mask->getAccessor();
    for (auto it = in.tree().cbeginValueOn(); it; ++it) {
      const openvdb::Vec3d w = xform->indexToWorld(it.getCoord());
      macc.setValueOn(openvdb::Coord::floor(out_xform->worldToIndex(w)));
    }
  }
  openvdb::tools::dilateActiveValues(mask->tree(), static_cast<int>(std::ceil(scale)) + 1,
                                     openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);
  std::vector<openvdb::MaskTree::LeafNodeType*> mleaves;
  mask->tree().getNodes(mleaves);
  std::vector<openvdb::Coord> origins;
  for (const auto* m : mleaves) origins.push_back(m->origin());
  return AssembleNarrowBand(spec, bg, origins, [&](size_t i, auto&& emit) {
    auto acc = in.getConstAccessor();  // one accessor per leaf (not thread-safe)
    for (auto it = mleaves[i]->cbeginValueOn(); it; ++it) {
      const openvdb::Vec3d w = out_xform->indexToWorld(it.getCoord());
      emit(it.pos(), scale * openvdb::tools::QuadraticSampler::sample(acc, xform->worldToIndex(w)), true);
    }
  });
}

bool IsLatticeShift(const Vec3& t, double vs, openvdb::Coord& shift) {
  for (int k = 0; k < 3; ++k) {
    const double n = t[k] / vs;
    const double r = std::round(n);
    if (std::abs(n - r) > 1e-9 || std::abs(r) > 1e9) return false;
    shift[k] = static_cast<openvdb::Int32>(r);
  }
  return true;
}

}  // namespace

// ---- Transforms -----------------------------------------------------------------

namespace {
// A mesh solid mapped vertex by vertex (x -> f(x)): it stays a mesh solid.
template <typename F>
Solid MapBoundary(const Solid& s, F&& f) {
  mesh::TriangleMesh m = *s.boundary();
  for (auto& v : m.vertices) v = f(v);
  return MeshSolid(s.impl()->spec, std::move(m));
}
}  // namespace

Solid Translate(const Solid& s, const Vec3& t) {
  for (double v : t)
    if (!std::isfinite(v)) throw InputError("translate: offset must be finite");
  if (!s.impl()) return s;
  if (s.boundary())
    return MapBoundary(s, [&](const std::array<double, 3>& v) {
      return std::array<double, 3>{v[0] + t[0], v[1] + t[1], v[2] + t[2]};
    });
  openvdb::Coord shift;
  if (IsLatticeShift(t, s.voxel_size(), shift)) {
    // Exact: move every active voxel by a whole number of voxels.
    const FloatGrid& src = *s.impl()->Grid();
    FloatGrid::Ptr out = EmptyGrid(s.impl()->spec);
    auto acc = out->getAccessor();
    for (auto it = src.tree().cbeginValueOn(); it; ++it) {
      if (it.isVoxelValue()) {
        acc.setValueOn(it.getCoord() + shift, *it);
      } else {
        openvdb::CoordBBox b = it.getBoundingBox();
        b.translate(shift);
        out->tree().fill(b, *it, true);
      }
    }
    openvdb::tools::signedFloodFill(out->tree());
    return internal::MakeSolid(out, s.impl()->spec);
  }
  return MapAndRebuild(s, [&](openvdb::math::Transform& x) { x.postTranslate(openvdb::Vec3d(t[0], t[1], t[2])); });
}

Solid Rotate(const Solid& s, const Vec3& euler_xyz_deg) {
  for (double v : euler_xyz_deg)
    if (!std::isfinite(v)) throw InputError("rotate: angles must be finite");
  if (!s.impl()) return s;
  if (euler_xyz_deg[0] == 0 && euler_xyz_deg[1] == 0 && euler_xyz_deg[2] == 0) return s;
  const double k = std::numbers::pi / 180.0;
  if (s.boundary()) {
    const double cx = std::cos(euler_xyz_deg[0] * k), sx = std::sin(euler_xyz_deg[0] * k);
    const double cy = std::cos(euler_xyz_deg[1] * k), sy = std::sin(euler_xyz_deg[1] * k);
    const double cz = std::cos(euler_xyz_deg[2] * k), sz = std::sin(euler_xyz_deg[2] * k);
    return MapBoundary(s, [&](const std::array<double, 3>& v) {
      const double y1 = cx * v[1] - sx * v[2], z1 = sx * v[1] + cx * v[2];     // about x
      const double x2 = cy * v[0] + sy * z1, z2 = -sy * v[0] + cy * z1;        // about y
      return std::array<double, 3>{cz * x2 - sz * y1, sz * x2 + cz * y1, z2};  // about z
    });
  }
  return MapAndRebuild(s, [&](openvdb::math::Transform& x) {
    // R = Rz * Ry * Rx on column vectors: rotate about x first.
    x.postRotate(euler_xyz_deg[0] * k, openvdb::math::X_AXIS);
    x.postRotate(euler_xyz_deg[1] * k, openvdb::math::Y_AXIS);
    x.postRotate(euler_xyz_deg[2] * k, openvdb::math::Z_AXIS);
  });
}

Solid Scale(const Solid& s, double factor) {
  internal::RequirePositive(factor, "scale", "factor");
  if (!s.impl()) return s;
  if (factor == 1.0) return s;
  if (s.boundary())
    return MapBoundary(s, [&](const std::array<double, 3>& v) {
      return std::array<double, 3>{v[0] * factor, v[1] * factor, v[2] * factor};
    });
  internal::CheckActiveVoxelEstimate(s.impl()->spec, ActiveVoxels(s) * factor * factor, "the scaled solid");
  return MapAndRebuild(
      s, [&](openvdb::math::Transform& x) { x.postScale(factor); }, factor);
}

}  // namespace fabatlas::geometry
