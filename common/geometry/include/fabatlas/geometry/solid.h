// fabatlas/geometry/solid.h — solids as narrow-band signed-distance level sets.
//
// A Solid wraps an OpenVDB FloatGrid level set (negative inside, background =
// half-width in world units) behind a pointer to an opaque implementation, so
// that no OpenVDB header reaches the code that includes this one. Solids are
// immutable values: every operation returns a new Solid and leaves its inputs
// untouched (OpenVDB's in-place CSG would empty its second grid; we copy).
//
// Units: millimetres and degrees. Every Solid built for one evaluation uses one
// GridSpec, i.e. one voxel size and one transform (voxel centres at integer
// multiples of voxel_size), because OpenVDB CSG works in index space and never
// checks transforms. Operations on Solids of different voxel sizes resample the
// second operand onto the first one's transform.
//
// Threading: operations use TBB internally (OpenVDB tools); callers that
// evaluate several samples in parallel nest them in task arenas.
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "fabatlas/mesh/triangle_mesh.h"
#include "fabatlas/vec3.h"

namespace fabatlas::geometry {

using fabatlas::Vec2;
using fabatlas::Vec3;

// Resolution of a level set: voxel edge length and narrow-band half width.
struct GridSpec {
  double voxel_size = 0.5;         // mm; must be > 0
  double half_width_voxels = 3.0;  // narrow band on each side, in voxels (>= 2)
  // Upper bound on the number of active voxels any single operation may
  // create; exceeding it throws InputError (protects memory on bad input).
  std::size_t max_active_voxels = 50'000'000;
};

struct Box3 {
  Vec3 min{0, 0, 0};
  Vec3 max{0, 0, 0};
};

class Solid {
 public:
  Solid();  // the empty solid (no material)

  bool empty() const;         // no interior voxel
  double voxel_size() const;  // mm (0 for a default-constructed Solid)

  // Volume enclosed by the zero level set, mm^3 (smooth Heaviside over the
  // narrow band; exact to within about one voxel layer of the surface).
  double Volume() const;
  // Centre of mass of the interior at uniform density, mm.
  Vec3 CenterOfMass() const;
  // Axis-aligned bounding box of the interior (zero level set), mm.
  Box3 BoundingBox() const;
  // Bytes the grid occupies in memory.
  std::size_t MemoryBytes() const;

  // Zero iso-surface via openvdb::tools::volumeToMesh, as triangles
  // (quads split), outward orientation. adaptivity in [0,1]. A mesh solid
  // (MeshSolid) returns its boundary as it is, whatever the adaptivity.
  mesh::TriangleMesh ToMesh(double adaptivity = 0.0) const;

  // The exact boundary of a mesh solid (MeshSolid), else nullptr.
  const mesh::TriangleMesh* boundary() const;

  // Exact, deterministic byte encoding (OpenVDB stream, uncompressed metadata
  // stripped of timestamps; a mesh solid's boundary as raw little-endian
  // doubles and indices) for content-addressed cache blobs, and back.
  std::string Serialize() const;
  static Solid Deserialize(std::string_view bytes);  // throws InputError

  struct Impl;
  explicit Solid(std::shared_ptr<const Impl> impl);
  const Impl* impl() const { return impl_.get(); }

 private:
  std::shared_ptr<const Impl> impl_;
};

// ---- Primitives (centred at the origin unless stated) ----------------------
Solid Sphere(const GridSpec& g, double radius);
Solid Box(const GridSpec& g, const Vec3& size);                   // edge lengths
Solid Cylinder(const GridSpec& g, double radius, double height);  // axis z
Solid Cone(const GridSpec& g, double bottom_radius, double top_radius,
           double height);                                                 // axis z, z in [-h/2,h/2]
Solid Torus(const GridSpec& g, double major_radius, double minor_radius);  // in xy-plane
Solid Capsule(const GridSpec& g, const Vec3& a, const Vec3& b, double radius);

// Extrude a simple closed polygon in the xy-plane (mm, either orientation)
// along z from 0 to height.
Solid Extrude(const GridSpec& g, const std::vector<Vec2>& polygon, double height);
// Revolve a closed profile polygon given as (r, z) points with r >= 0 about the
// z axis. sides == 0: smooth surface of revolution; sides >= 3: the revolution
// has a regular n-gon cross-section (profile r is the circumradius), as the
// chess pieces and vase of Fab Forms.
Solid Revolve(const GridSpec& g, const std::vector<Vec2>& profile, int sides);
// Level set of a closed triangle mesh (orientation does not matter): exact
// signed distance sampled in the band when the mesh is closed and convex (up
// to 20,000 triangles), else OpenVDB meshToLevelSet. Open meshes are signed
// by OpenVDB's flood fill, which may leak; throws InputError if no interior results, or on bad indices/NaNs.
// (Winding-number signing of open meshes is not implemented yet.)
Solid FromMesh(const GridSpec& g, const mesh::TriangleMesh& m);

// A solid bounded by a closed, outward triangle mesh taken as exact: the
// mesh road of OpenSCAD models (docs/openscad.md). Volume, CenterOfMass and
// BoundingBox are the mesh's own (divergence theorem, exact up to rounding),
// ToMesh returns the mesh, MemoryBytes counts the mesh, and DeltaG of two
// mesh solids integrates the meshes along columns. Every other operation (level-set
// CSG, offsets, occupancy, opening) reads the level set on `g`, built from the
// mesh by FromMesh the first time one asks (once per solid, thread-safe).
// An empty mesh is the empty solid. Throws InputError on a missing vertex or
// a coordinate that is not finite.
Solid MeshSolid(const GridSpec& g, mesh::TriangleMesh boundary);

// Level set of a signed distance function f(x, y, z) (mm, negative inside)
// whose interior lies within `bounds`. f must be exact within the narrow band
// and never exceed the true distance in magnitude elsewhere (a bound, as CSG
// min/max of exact distances is): blocks of voxels whose centre value rules
// out the band are skipped, so the cost grows with the surface area. f is
// called concurrently from TBB tasks. `what` names the shape in errors.
using DistanceFunction = std::function<double(double x, double y, double z)>;
Solid FromDistance(const GridSpec& g, const Box3& bounds, const DistanceFunction& f, const char* what);

// ---- Transforms (rotations in degrees, applied as R = Rz*Ry*Rx) ------------
Solid Translate(const Solid& s, const Vec3& t);
Solid Rotate(const Solid& s, const Vec3& euler_xyz_deg);
Solid Scale(const Solid& s, double factor);

// ---- CSG and offsets --------------------------------------------------------
Solid Union(const Solid& a, const Solid& b);
// Difference removes the zero-thickness sheets that faces the operands share
// would leave on voxel centres (a hole's caps flush with the solid's):
// extraction artefacts of sub-voxel features (docs/geometry.md).
Solid Difference(const Solid& a, const Solid& b);  // a minus b
Solid Intersection(const Solid& a, const Solid& b);
// Outward offset by distance mm (negative = inward); the narrow band is widened
// first so the iso-value stays inside it.
Solid Offset(const Solid& s, double distance);
// Hollow shell of the given wall thickness inside the original surface.
Solid Shell(const Solid& s, double thickness);
// count copies, the i-th translated by i*step (i = 0..count-1), unioned.
Solid LinearArray(const Solid& s, int count, const Vec3& step);
// count copies rotated about the z axis by i*total_angle_deg/count, unioned.
Solid PolarArray(const Solid& s, int count, double total_angle_deg);

// ---- Measures -----------------------------------------------------------------
// Volumetric change of Fab Forms Eq. 2: |A xor B| / |A union B|, in [0,1].
// Both empty -> 0. One empty, other not -> 1. Two mesh solids: |A|, |B|, |A n B|
// integrated along vertical columns one voxel apart (mesh::IntegrateColumnOverlap),
// |A xor B| = |A| + |B| - 2|A n B|, |A u B| = |A| + |B| - |A n B|; otherwise
// from level-set CSG.
double DeltaG(const Solid& a, const Solid& b);

// Minimum-feature test by morphological opening (OpenVDB erosion then
// dilation): the fraction of the solid's volume that disappears when opened
// with a ball of radius min_thickness/2. Thin features vanish under opening.
double OpeningLossFraction(const Solid& s, double min_thickness);

// Dense inside/outside sampling on a regular grid of cubic cells, e.g. the
// voxel hexahedra of the FEM check (Fab Forms Sec. 8, docs/fem.md), whose
// resolution is independent of the level set's voxel size. Cell (i,j,k) is
// the box [origin + (i,j,k)*cell_size, origin + (i+1,j+1,k+1)*cell_size] (mm);
// it is inside iff the level set, trilinearly interpolated at the cell centre,
// is negative. Cell corners lie on integer multiples of cell_size, and the
// cells cover the solid's bounding box.
struct Occupancy {
  Vec3 origin{0, 0, 0};               // min corner of cell (0,0,0), mm
  double cell_size = 0;               // mm
  std::array<int, 3> dims{0, 0, 0};   // all 0 for the empty solid
  std::vector<unsigned char> inside;  // inside[i + dims[0]*(j + dims[1]*k)]: 1 or 0
  std::size_t inside_count = 0;       // number of cells with inside == 1
};
// Throws InputError if cell_size is not finite and > 0, or if the covering
// grid would have more than max_cells cells. Threading: TBB over z slices.
Occupancy SampleOccupancy(const Solid& s, double cell_size, std::size_t max_cells = 20'000'000);

}  // namespace fabatlas::geometry
