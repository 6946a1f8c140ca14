// operations.cc — CSG, offsets, arrays and the measures built on them (ΔG of
// Fab Forms Eq. 2, morphological opening); transforms are in transforms.cc.
#include <openvdb/tools/Composite.h>
#include <openvdb/tools/LevelSetRebuild.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>

#include "fabatlas/mesh/column_overlap.h"
#include "narrow_band.h"
#include "solid_impl.h"

namespace fabatlas::geometry {

using openvdb::FloatGrid;
using LeafT = openvdb::FloatTree::LeafNodeType;

FloatGrid::Ptr internal::EmptyGrid(const GridSpec& spec) {
  FloatGrid::Ptr grid = FloatGrid::create(static_cast<float>(spec.half_width_voxels * spec.voxel_size));
  grid->setTransform(internal::CanonicalTransform(spec.voxel_size));
  return grid;
}

Solid internal::EmptyLike(const Solid& s) { return internal::MakeSolid(EmptyGrid(s.impl()->spec), s.impl()->spec); }

double internal::ActiveVoxels(const Solid& s) { return static_cast<double>(s.impl()->Grid()->activeVoxelCount()); }

Solid internal::Rebuild(const FloatGrid& src, const GridSpec& spec) {
  auto xform = internal::CanonicalTransform(spec.voxel_size);
  const float hw = static_cast<float>(spec.half_width_voxels);
  FloatGrid::Ptr out =
      openvdb::tools::levelSetRebuild(src, static_cast<float>(kMeshIso * src.voxelSize()[0]), hw, hw, xform.get());
  return internal::MakeSolid(out, spec);
}

namespace {

using internal::ActiveVoxels;
using internal::AssembleNarrowBand;
using internal::EmptyLike;
using internal::Rebuild;

// `b` expressed on `a`'s grid spec (voxel size, band), resampling if needed.
FloatGrid::ConstPtr OnSpecOf(const Solid& a, const Solid& b) {
  const GridSpec& sa = a.impl()->spec;
  const GridSpec& sb = b.impl()->spec;
  if (sa.voxel_size == sb.voxel_size && sa.half_width_voxels == sb.half_width_voxels) return b.impl()->Grid();
  GridSpec target = sa;
  return Rebuild(*b.impl()->Grid(), target).impl()->Grid();
}

}  // namespace

// ---- CSG ------------------------------------------------------------------------

Solid Union(const Solid& a, const Solid& b) {
  if (!a.impl()) return b;
  if (!b.impl()) return a;
  return internal::MakeSolid(openvdb::tools::csgUnionCopy(*a.impl()->Grid(), *OnSpecOf(a, b)), a.impl()->spec);
}

// A sub-voxel sheet between flush faces (solid_impl.h): such a voxel takes the
// smaller neighbour value; genuine material is negative and never changes.
std::size_t internal::RemoveZeroSheets(FloatGrid& grid, double voxel_size) {
  const float iso = static_cast<float>(kMeshIso * voxel_size);
  // Found leaf by leaf in parallel (every fix reads the unrepaired grid),
  // then applied.
  std::vector<const LeafT*> leaves;
  grid.tree().getNodes(leaves);
  std::vector<std::vector<std::pair<openvdb::Coord, float>>> per_leaf(leaves.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.size()), [&](const tbb::blocked_range<size_t>& r) {
    auto acc = grid.getConstAccessor();
    internal::LeafCache<decltype(acc)> neighbours;
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const float* values = leaves[i]->buffer().data();
      for (auto on = leaves[i]->getValueMask().beginOn(); on; ++on) {
        const float v = values[on.pos()];
        if (v < 0 || v > iso) continue;
        const openvdb::Coord local = LeafT::offsetToLocalCoord(on.pos());
        const openvdb::Coord c = leaves[i]->origin() + local;
        for (int axis = 0; axis < 3; ++axis) {
          // Neighbours inside the leaf from its buffer, across its faces
          // from theirs (LeafCache).
          const openvdb::Index step = 1u << (LeafT::LOG2DIM * (2 - axis));
          const bool inner = local[axis] > 0 && local[axis] < static_cast<int>(LeafT::DIM) - 1;
          openvdb::Coord lo = c, hi = c;
          lo[axis] -= 1;
          hi[axis] += 1;
          const float a = inner ? values[on.pos() - step] : neighbours.Value(acc, lo);
          const float b = inner ? values[on.pos() + step] : neighbours.Value(acc, hi);
          if (a > iso && b > iso) {
            per_leaf[i].emplace_back(c, std::min(a, b));
            break;
          }
        }
      }
    }
  });
  std::size_t fixed = 0;
  auto out = grid.getAccessor();
  for (const auto& fixes : per_leaf) {
    for (const auto& [c, v] : fixes) out.setValue(c, v);
    fixed += fixes.size();
  }
  // OpenVDB's CSG keeps the first operand's inactive interior values where
  // the second operand removed material (a hole's inside stays "inside"):
  // re-sign every inactive value from the active band, as the volume and
  // centre of mass read them.
  openvdb::tools::signedFloodFill(grid.tree());
  return fixed;
}

Solid Difference(const Solid& a, const Solid& b) {
  if (!a.impl()) return a;
  if (!b.impl()) return a;
  FloatGrid::Ptr out = openvdb::tools::csgDifferenceCopy(*a.impl()->Grid(), *OnSpecOf(a, b));
  internal::RemoveZeroSheets(*out, a.voxel_size());
  return internal::MakeSolid(out, a.impl()->spec);
}

Solid Intersection(const Solid& a, const Solid& b) {
  if (!a.impl()) return a;
  if (!b.impl()) return b;
  return internal::MakeSolid(openvdb::tools::csgIntersectionCopy(*a.impl()->Grid(), *OnSpecOf(a, b)), a.impl()->spec);
}

// ---- Offsets --------------------------------------------------------------------

Solid Offset(const Solid& s, double distance) {
  if (!std::isfinite(distance)) throw InputError("offset: distance must be finite");
  if (!s.impl() || distance == 0) return s;
  if (s.empty()) return EmptyLike(s);
  const GridSpec& spec = s.impl()->spec;
  const double vs = spec.voxel_size;
  const int dilation = static_cast<int>(std::ceil(std::abs(distance) / vs)) + 2;
  const double band_growth = (spec.half_width_voxels + dilation) / spec.half_width_voxels;
  internal::CheckActiveVoxelEstimate(spec, ActiveVoxels(s) * band_growth, "the widened offset band");
  if (distance > 0) {
    const Box3 b = s.BoundingBox();
    internal::CheckVoxelBudget(
        spec,
        {b.max[0] - b.min[0] + 2 * distance, b.max[1] - b.min[1] + 2 * distance, b.max[2] - b.min[2] + 2 * distance},
        "offset solid");
  }
  // Exact distances (to the mesh of the zero level set) in a band widened on
  // the side we move towards, then a standard band around the iso-value.
  const float hw = static_cast<float>(spec.half_width_voxels);
  const float widened = hw + static_cast<float>(dilation);
  const FloatGrid& in = *s.impl()->Grid();
  const float iso0 = static_cast<float>(kMeshIso * vs);
  FloatGrid::Ptr wide =
      openvdb::tools::levelSetRebuild(in, iso0, distance > 0 ? widened : hw, distance < 0 ? widened : hw);
  // phi - distance is the signed distance to the offset surface (exact on the
  // side the surface moved towards, a lower bound at creases); keep the band.
  const double bg = spec.half_width_voxels * vs;
  std::vector<LeafT*> wide_leaves;
  wide->tree().getNodes(wide_leaves);
  std::vector<openvdb::Coord> origins;
  for (const auto* l : wide_leaves) origins.push_back(l->origin());
  return AssembleNarrowBand(spec, bg, origins, [&](size_t i, auto&& emit) {
    for (auto it = wide_leaves[i]->cbeginValueAll(); it; ++it)
      emit(it.pos(), static_cast<double>(*it) - distance, it.isValueOn());
  });
}

Solid Shell(const Solid& s, double thickness) {
  internal::RequirePositive(thickness, "shell", "thickness");
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
  internal::CheckActiveVoxelEstimate(s.impl()->spec, ActiveVoxels(s) * count, "the linear array");
  std::vector<Solid> parts;
  parts.reserve(count);
  for (int i = 0; i < count; ++i) parts.push_back(Translate(s, {i * step[0], i * step[1], i * step[2]}));
  return UnionRange(parts, 0, parts.size());
}

Solid PolarArray(const Solid& s, int count, double total_angle_deg) {
  if (count < 1) throw InputError("polar array: count must be >= 1");
  if (!std::isfinite(total_angle_deg)) throw InputError("polar array: angle must be finite");
  if (!s.impl()) return s;
  internal::CheckActiveVoxelEstimate(s.impl()->spec, ActiveVoxels(s) * count, "the polar array");
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
  if (a.boundary() && b.boundary()) {
    // Equal meshes (samples whose parameters do not change the geometry):
    // no change, without intersecting a mesh with its own coplanar twin.
    if (a.boundary()->vertices == b.boundary()->vertices && a.boundary()->triangles == b.boundary()->triangles)
      return 0.0;
    // Two exact meshes: |A|, |B| and |A ∩ B| integrated along vertical
    // columns one voxel apart (mesh/column_overlap.h). Corefining two
    // settings of one model, which share most of their faces, took seconds
    // to minutes (doubles, then exact constructions); the columns take
    // milliseconds and err as a level set of that voxel size does.
    const double spacing = std::min(a.voxel_size(), b.voxel_size());
    if (spacing > 0) {
      const mesh::ColumnOverlap c = mesh::IntegrateColumnOverlap(*a.boundary(), *b.boundary(), spacing);
      const double vu = c.volume_a + c.volume_b - c.volume_both;
      if (vu <= 0) return 0.0;
      return std::clamp((vu - c.volume_both) / vu, 0.0, 1.0);
    }
  }
  const double vu = Union(a, b).Volume();
  const double vi = Intersection(a, b).Volume();
  if (vu <= 0) return 0.0;
  return std::clamp((vu - vi) / vu, 0.0, 1.0);
}

double OpeningLossFraction(const Solid& s, double min_thickness) {
  internal::RequirePositive(min_thickness, "opening", "minimum thickness");
  if (s.empty()) return 0.0;
  const double v = s.Volume();
  const double r = min_thickness / 2;
  const Solid eroded = Offset(s, -r);
  if (eroded.empty()) return 1.0;
  const Solid opened = Offset(eroded, r);
  return std::clamp((v - opened.Volume()) / v, 0.0, 1.0);
}

}  // namespace fabatlas::geometry
