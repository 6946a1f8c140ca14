// operations.cc — transforms, CSG, offsets, arrays and the measures built on
// them (ΔG of Fab Forms Eq. 2, morphological opening).
#include <openvdb/tools/Composite.h>
#include <openvdb/tools/LevelSetRebuild.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>

#include "fabatlas/mesh/column_overlap.h"
#include "solid_impl.h"

namespace fabatlas::geometry {

using openvdb::FloatGrid;
using LeafT = openvdb::FloatTree::LeafNodeType;

namespace {

FloatGrid::Ptr EmptyGrid(const GridSpec& spec) {
  FloatGrid::Ptr grid = FloatGrid::create(static_cast<float>(spec.half_width_voxels * spec.voxel_size));
  grid->setTransform(internal::CanonicalTransform(spec.voxel_size));
  return grid;
}

Solid EmptyLike(const Solid& s) { return internal::MakeSolid(EmptyGrid(s.impl()->spec), s.impl()->spec); }

double ActiveVoxels(const Solid& s) { return static_cast<double>(s.impl()->Grid()->activeVoxelCount()); }

// Rebuild the zero level set of `src` (whose transform may be any affine map)
// as a narrow band on the canonical transform of `spec`.
Solid Rebuild(const FloatGrid& src, const GridSpec& spec) {
  auto xform = internal::CanonicalTransform(spec.voxel_size);
  const float hw = static_cast<float>(spec.half_width_voxels);
  FloatGrid::Ptr out =
      openvdb::tools::levelSetRebuild(src, static_cast<float>(kMeshIso * src.voxelSize()[0]), hw, hw, xform.get());
  return internal::MakeSolid(out, spec);
}

// `b` expressed on `a`'s grid spec (voxel size, band), resampling if needed.
FloatGrid::ConstPtr OnSpecOf(const Solid& a, const Solid& b) {
  const GridSpec& sa = a.impl()->spec;
  const GridSpec& sb = b.impl()->spec;
  if (sa.voxel_size == sb.voxel_size && sa.half_width_voxels == sb.half_width_voxels) return b.impl()->Grid();
  GridSpec target = sa;
  return Rebuild(*b.impl()->Grid(), target).impl()->Grid();
}

// Builds a narrow-band level set leaf by leaf, in parallel over leaves (TBB):
// `fill(i, emit)` visits the candidate voxels of the leaf at origins[i] and
// calls emit(pos, v, candidate). A voxel becomes active with value v when it
// is a candidate and |v| is inside the band half width `bg` (world units);
// every other visited voxel is stored inactive at +bg or -bg by the sign of
// v. Leaves with no active voxel are dropped; the result is sign-flooded.
// `fill` runs concurrently for different i and must be thread-safe.
template <class Fill>
Solid AssembleNarrowBand(const GridSpec& spec, double bg, const std::vector<openvdb::Coord>& origins, Fill fill) {
  std::vector<LeafT*> out_leaves(origins.size(), nullptr);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, origins.size()), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      auto leaf = std::make_unique<LeafT>(origins[i], static_cast<float>(bg), false);
      bool any = false;
      fill(i, [&](openvdb::Index pos, double v, bool candidate) {
        if (candidate && std::abs(v) < bg) {
          leaf->setValueOn(pos, static_cast<float>(v));
          any = true;
        } else {
          leaf->setValueOff(pos, static_cast<float>(v > 0 ? bg : -bg));
        }
      });
      if (any) out_leaves[i] = leaf.release();
    }
  });
  FloatGrid::Ptr out = EmptyGrid(spec);
  for (LeafT* leaf : out_leaves)
    if (leaf) out->tree().addLeaf(leaf);
  openvdb::tools::signedFloodFill(out->tree());
  return internal::MakeSolid(out, spec);
}

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
