// operations.cpp — transforms, CSG, offsets, arrays and the measures built on
// them (ΔG of seed 001 Eq. 2, morphological opening).
#include <openvdb/tools/Composite.h>
#include <openvdb/tools/FastSweeping.h>
#include <openvdb/tools/LevelSetRebuild.h>
#include <openvdb/tools/SignedFloodFill.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "solid_impl.h"

namespace fabatlas::geometry {

using openvdb::FloatGrid;

namespace {

FloatGrid::Ptr EmptyGrid(const GridSpec& spec) {
  FloatGrid::Ptr grid = FloatGrid::create(static_cast<float>(spec.half_width_voxels * spec.voxel_size));
  grid->setTransform(detail::CanonicalTransform(spec.voxel_size));
  return grid;
}

Solid EmptyLike(const Solid& s) { return detail::MakeSolid(EmptyGrid(s.impl()->spec), s.impl()->spec); }

double ActiveVoxels(const Solid& s) { return static_cast<double>(s.impl()->grid->activeVoxelCount()); }

// Rebuild the zero level set of `src` (whose transform may be any affine map)
// as a narrow band on the canonical transform of `spec`.
Solid Rebuild(const FloatGrid& src, const GridSpec& spec) {
  auto xform = detail::CanonicalTransform(spec.voxel_size);
  const float hw = static_cast<float>(spec.half_width_voxels);
  FloatGrid::Ptr out = openvdb::tools::levelSetRebuild(src, 0.0f, hw, hw, xform.get());
  return detail::MakeSolid(out, spec);
}

// `b` expressed on `a`'s grid spec (voxel size, band), resampling if needed.
FloatGrid::ConstPtr OnSpecOf(const Solid& a, const Solid& b) {
  const GridSpec& sa = a.impl()->spec;
  const GridSpec& sb = b.impl()->spec;
  if (sa.voxel_size == sb.voxel_size && sa.half_width_voxels == sb.half_width_voxels) return b.impl()->grid;
  GridSpec target = sa;
  return Rebuild(*b.impl()->grid, target).impl()->grid;
}

// Resample s after mapping its geometry by `post` (applied after s's
// canonical index-to-world map).
template <typename Fn>
Solid MapAndRebuild(const Solid& s, Fn post) {
  FloatGrid::Ptr src = s.impl()->grid->copy();  // shares the tree, own transform
  auto xform = s.impl()->grid->transform().copy();
  post(*xform);
  src->setTransform(xform);
  return Rebuild(*src, s.impl()->spec);
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

Solid Translate(const Solid& s, const Vec3& t) {
  for (double v : t)
    if (!std::isfinite(v)) throw InputError("translate: offset must be finite");
  if (!s.impl()) return s;
  openvdb::Coord shift;
  if (IsLatticeShift(t, s.voxel_size(), shift)) {
    // Exact: move every active voxel by a whole number of voxels.
    const FloatGrid& src = *s.impl()->grid;
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
    return detail::MakeSolid(out, s.impl()->spec);
  }
  return MapAndRebuild(s, [&](openvdb::math::Transform& x) { x.postTranslate(openvdb::Vec3d(t[0], t[1], t[2])); });
}

Solid Rotate(const Solid& s, const Vec3& euler_xyz_deg) {
  for (double v : euler_xyz_deg)
    if (!std::isfinite(v)) throw InputError("rotate: angles must be finite");
  if (!s.impl()) return s;
  if (euler_xyz_deg[0] == 0 && euler_xyz_deg[1] == 0 && euler_xyz_deg[2] == 0) return s;
  const double k = std::numbers::pi / 180.0;
  return MapAndRebuild(s, [&](openvdb::math::Transform& x) {
    // R = Rz * Ry * Rx on column vectors: rotate about x first.
    x.postRotate(euler_xyz_deg[0] * k, openvdb::math::X_AXIS);
    x.postRotate(euler_xyz_deg[1] * k, openvdb::math::Y_AXIS);
    x.postRotate(euler_xyz_deg[2] * k, openvdb::math::Z_AXIS);
  });
}

Solid Scale(const Solid& s, double factor) {
  detail::RequirePositive(factor, "scale", "factor");
  if (!s.impl()) return s;
  if (factor == 1.0) return s;
  detail::CheckActiveVoxelEstimate(s.impl()->spec, ActiveVoxels(s) * factor * factor, "the scaled solid");
  return MapAndRebuild(s, [&](openvdb::math::Transform& x) { x.postScale(factor); });
}

// ---- CSG ------------------------------------------------------------------------

Solid Union(const Solid& a, const Solid& b) {
  if (!a.impl()) return b;
  if (!b.impl()) return a;
  return detail::MakeSolid(openvdb::tools::csgUnionCopy(*a.impl()->grid, *OnSpecOf(a, b)), a.impl()->spec);
}

Solid Difference(const Solid& a, const Solid& b) {
  if (!a.impl()) return a;
  if (!b.impl()) return a;
  return detail::MakeSolid(openvdb::tools::csgDifferenceCopy(*a.impl()->grid, *OnSpecOf(a, b)), a.impl()->spec);
}

Solid Intersection(const Solid& a, const Solid& b) {
  if (!a.impl()) return a;
  if (!b.impl()) return b;
  return detail::MakeSolid(openvdb::tools::csgIntersectionCopy(*a.impl()->grid, *OnSpecOf(a, b)),
                           a.impl()->spec);
}

// ---- Offsets --------------------------------------------------------------------

Solid Offset(const Solid& s, double distance) {
  if (!std::isfinite(distance)) throw InputError("offset: distance must be finite");
  if (!s.impl() || distance == 0) return s;
  if (s.empty()) return EmptyLike(s);
  const GridSpec& spec = s.impl()->spec;
  const double vs = spec.voxel_size;
  // Widen the band on the side we move towards (fast sweeping, an Eikonal
  // solve) so that the iso-value `distance` lies well inside it, then rebuild
  // a standard narrow band around that iso-surface.
  const int dilation = static_cast<int>(std::ceil(std::abs(distance) / vs)) + 2;
  const double band_growth = (spec.half_width_voxels + dilation) / spec.half_width_voxels;
  detail::CheckActiveVoxelEstimate(spec, ActiveVoxels(s) * band_growth, "the widened offset band");
  if (distance > 0) {
    const Box3 b = s.BoundingBox();
    detail::CheckVoxelBudget(spec,
                             {b.max[0] - b.min[0] + 2 * distance, b.max[1] - b.min[1] + 2 * distance,
                              b.max[2] - b.min[2] + 2 * distance},
                             "offset solid");
  }
  const auto mode = distance > 0 ? openvdb::tools::FastSweepingDomain::SWEEP_GREATER_THAN_ISOVALUE
                                 : openvdb::tools::FastSweepingDomain::SWEEP_LESS_THAN_ISOVALUE;
  FloatGrid::Ptr wide = openvdb::tools::dilateSdf(*s.impl()->grid, dilation, openvdb::tools::NN_FACE, 1, mode);
  const float hw = static_cast<float>(spec.half_width_voxels);
  FloatGrid::Ptr out = openvdb::tools::levelSetRebuild(*wide, static_cast<float>(distance), hw, hw);
  out->setTransform(detail::CanonicalTransform(vs));
  return detail::MakeSolid(out, spec);
}

Solid Shell(const Solid& s, double thickness) {
  detail::RequirePositive(thickness, "shell", "thickness");
  return Difference(s, Offset(s, -thickness));
}

namespace {
// Union of parts[lo, hi) as a balanced tree (each union copies its inputs).
Solid UnionRange(const std::vector<Solid>& parts, size_t lo, size_t hi) {
  if (hi - lo == 1) return parts[lo];
  const size_t mid = lo + (hi - lo) / 2;
  return Union(UnionRange(parts, lo, mid), UnionRange(parts, mid, hi));
}
}  // namespace

Solid LinearArray(const Solid& s, int count, const Vec3& step) {
  if (count < 1) throw InputError("linear array: count must be >= 1");
  for (double v : step)
    if (!std::isfinite(v)) throw InputError("linear array: step must be finite");
  if (!s.impl()) return s;
  detail::CheckActiveVoxelEstimate(s.impl()->spec, ActiveVoxels(s) * count, "the linear array");
  std::vector<Solid> parts;
  parts.reserve(count);
  for (int i = 0; i < count; ++i) parts.push_back(Translate(s, {i * step[0], i * step[1], i * step[2]}));
  return UnionRange(parts, 0, parts.size());
}

Solid PolarArray(const Solid& s, int count, double total_angle_deg) {
  if (count < 1) throw InputError("polar array: count must be >= 1");
  if (!std::isfinite(total_angle_deg)) throw InputError("polar array: angle must be finite");
  if (!s.impl()) return s;
  detail::CheckActiveVoxelEstimate(s.impl()->spec, ActiveVoxels(s) * count, "the polar array");
  std::vector<Solid> parts;
  parts.reserve(count);
  for (int i = 0; i < count; ++i) parts.push_back(Rotate(s, {0, 0, i * total_angle_deg / count}));
  return UnionRange(parts, 0, parts.size());
}

// ---- Measures -------------------------------------------------------------------

double DeltaG(const Solid& a, const Solid& b) {
  const bool ea = a.empty(), eb = b.empty();
  if (ea && eb) return 0.0;
  if (ea != eb) return 1.0;
  const double vu = Union(a, b).Volume();
  const double vi = Intersection(a, b).Volume();
  if (vu <= 0) return 0.0;
  return std::clamp((vu - vi) / vu, 0.0, 1.0);
}

double OpeningLossFraction(const Solid& s, double min_thickness) {
  detail::RequirePositive(min_thickness, "opening", "minimum thickness");
  if (s.empty()) return 0.0;
  const double v = s.Volume();
  const double r = min_thickness / 2;
  const Solid eroded = Offset(s, -r);
  if (eroded.empty()) return 1.0;
  const Solid opened = Offset(eroded, r);
  return std::clamp((v - opened.Volume()) / v, 0.0, 1.0);
}

}  // namespace fabatlas::geometry
