// solid_impl.h — the OpenVDB side of fabatlas::geometry::Solid (internal).
#pragma once

#include <openvdb/openvdb.h>

#include <array>
#include <mutex>
#include <string>

#include "fabatlas/error.h"
#include "fabatlas/geometry/solid.h"

namespace fabatlas::geometry {

// A level set grid (GRID_LEVEL_SET, background = half_width_voxels *
// voxel_size) whose transform is the canonical one of its GridSpec: a linear
// transform with voxel centres at integer multiples of voxel_size.
//
// A solid bounded by an exact mesh (MeshSolid, the mesh road) keeps `boundary`
// and builds its level set from it on first use (Grid(), once, thread-safe),
// so that a sample whose checks read only the mesh never voxelises it.
struct Solid::Impl {
  // The level set; never mutated after it is set.
  const openvdb::FloatGrid::Ptr& Grid() const;
  GridSpec spec;
  std::shared_ptr<const mesh::TriangleMesh> boundary;  // null: a level-set solid
  mutable openvdb::FloatGrid::Ptr grid;                // set at construction, or by Grid() from `boundary`
  mutable std::once_flag grid_once;
  // The inside's zeroth and first moments (voxel units: m0, m1 x, y, z) and
  // its bounding box (mm), computed together once for Volume, CenterOfMass
  // and BoundingBox (a sample asks for all three: the volume and bbox
  // properties and the stands check); thread-safe.
  mutable std::once_flag measures_once;
  mutable std::array<double, 4> moments{};
  mutable Box3 box{};
};

// Iso-value used when meshing a level set, in voxels (see Solid::ToMesh).
inline constexpr double kMeshIso = 1e-4;

namespace internal {

// openvdb::initialize() once per process (grid type registry, used by io).
void EnsureOpenVdbInitialized();

// Throws InputError unless spec is usable (finite voxel size > 0, half width >= 2).
void ValidateSpec(const GridSpec& spec, const char* where);

// Canonical transform of a spec: world = index * voxel_size.
openvdb::math::Transform::Ptr CanonicalTransform(double voxel_size);

// Throws InputError when a solid spanning `extent` (mm, per axis) would need
// more active voxels than spec.max_active_voxels. The estimate is the area of
// the extent's bounding box in voxels times the band thickness (2 * half
// width + 1 voxels): an upper bound for convex shapes.
void CheckVoxelBudget(const GridSpec& spec, const Vec3& extent, const char* what);
// Same guard for an operation whose output is expected to hold about
// `estimated_active` active voxels.
void CheckActiveVoxelEstimate(const GridSpec& spec, double estimated_active, const char* what);

// Wrap a finished grid as a Solid (sets class, name; grid must be canonical).
Solid MakeSolid(openvdb::FloatGrid::Ptr grid, const GridSpec& spec);

// Faces two CSG operands share make max(d_a, -d_b) exactly 0 on a plane of
// voxel centres with no material on either side: a zero-thickness sheet the
// mesh extraction would close into a slab. Such voxels (0 <= value <= iso,
// both neighbours along some axis outside) take the smaller neighbour value,
// then inactive values are signed again (operations.cc). Returns the voxels
// repaired.
std::size_t RemoveZeroSheets(openvdb::FloatGrid& grid, double voxel_size);
// The leaves of a float grid met lately, by origin (direct-mapped, 16
// slots), for reading voxels on both sides of leaf faces: where a surface
// lies on a multiple of 8 voxels (a box face at a round coordinate), each
// switch of leaf through an accessor walks the tree, from the root's map
// across root and internal node boundaries. A slot holds nullptr for a tile
// or background region. Not thread-safe: one per thread, with its accessor.
template <typename AccessorT>
class LeafCache {
 public:
  using LeafT = openvdb::FloatTree::LeafNodeType;
  // The value at p: its leaf's buffer, else the accessor's (the same value).
  float Value(AccessorT& acc, const openvdb::Coord& p) {
    constexpr int kMask = ~(static_cast<int>(LeafT::DIM) - 1);
    const openvdb::Coord origin(p.x() & kMask, p.y() & kMask, p.z() & kMask);
    const unsigned slot =
        (static_cast<unsigned>(origin.x()) * 73856093u ^ static_cast<unsigned>(origin.y()) * 19349663u ^
         static_cast<unsigned>(origin.z()) * 83492791u) >>
            3 &
        (kSlots - 1);
    if (!valid_[slot] || origin_[slot] != origin) {
      origin_[slot] = origin;
      leaf_[slot] = acc.probeConstLeaf(p);
      valid_[slot] = true;
    }
    return leaf_[slot] ? leaf_[slot]->buffer().data()[LeafT::coordToOffset(p)] : acc.getValue(p);
  }

 private:
  static constexpr unsigned kSlots = 16;
  openvdb::Coord origin_[kSlots];
  const LeafT* leaf_[kSlots] = {};
  bool valid_[kSlots] = {};
};

// Throws InputError with `where: message` unless value is finite and > 0.
void RequirePositive(double value, const char* where, const char* name);

}  // namespace internal
}  // namespace fabatlas::geometry
