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
struct Solid::Impl {
  openvdb::FloatGrid::Ptr grid;  // never mutated after construction
  GridSpec spec;
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

namespace detail {

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
// Throws InputError with `where: message` unless value is finite and > 0.
void RequirePositive(double value, const char* where, const char* name);

}  // namespace detail
}  // namespace fabatlas::geometry
