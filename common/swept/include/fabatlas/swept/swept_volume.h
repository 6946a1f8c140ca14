// fabatlas/swept/swept_volume.h — signed distance to a swept volume on a
// sparse grid, and its epsilon-offset surface (Reconfigurables, section 6.7).
//
// The swept volume of a body B under a rigid motion f is S = U_t f(t)B and
//   d(S, p) = min_t d(f(t)B, p)                       (Reconfigurables, Eq. 5)
// evaluated at discrete times t_i. Unlike the dense method of the seed (every
// grid vertex, every time step, one closest-point query), we build B's narrow
// band level set once (OpenVDB meshToLevelSet) and, at each step, touch only
// the world voxels within the band of f(t_i)B: B's band voxels are mapped by
// f(t_i), rounded to the world lattice and dilated by one voxel (26-
// neighbourhood), and each touched voxel takes the min with B's level set
// sampled (trilinear) at f(t_i)^-1 p. Afterwards the inactive interior is
// signed by flood fill and the epsilon-offset surface is the iso-epsilon
// surface (OpenVDB volumeToMesh).
//
// Why the band suffices: a voxel's distance changes between two steps by at
// most the Hausdorff distance between the two body poses, which is the
// largest displacement of a corner of B's bounding box. The band half width
// is made larger than that, so a voxel that passes from deep inside to
// outside is seen inside the band on the way and keeps a value <= 0.
//
// Units: millimetres. Threading: TBB over grid leaves inside each step.
// Accuracy: values are within about voxel_size^2 / (8 r) of the sampled-in-
// time distance for surfaces of curvature radius r, plus the chord error of
// the time sampling (the automatic step count keeps the largest displacement
// per step at or below `max_step_displacement`).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "fabatlas/geometry/solid.h"
#include "fabatlas/mesh/triangle_mesh.h"
#include "fabatlas/swept/rigid_motion.h"

namespace fabatlas::swept {

struct SweptVolumeOptions {
  double voxel_size = 0.5;  // h, mm (> 0)
  double offset = 0.0;      // epsilon of the offset surface, mm (>= 0)
  // Minimum number of time samples t_i = i/(n-1) (>= 2). More are used when
  // needed to keep every point's displacement per step <= max_step_displacement.
  int time_steps = 2;
  // Largest allowed displacement of any body point between two time samples,
  // mm; 0 means one voxel_size.
  double max_step_displacement = 0.0;
  // Narrow band half width in voxels (>= 2); widened automatically to cover
  // offset + 2 voxels and the per-step displacement + 2 voxels.
  double half_width_voxels = 3.0;
  // Guard on the number of active voxels of the result (throws ResourceError).
  std::size_t max_active_voxels = 50'000'000;
};

struct SweptVolumeSummary {
  int time_steps = 0;                // samples actually used
  double band_half_width = 0;        // mm
  std::size_t body_band_voxels = 0;  // voxels of B's band mapped per step
  std::uint64_t voxel_updates = 0;   // level-set samples taken over all steps
  std::size_t active_voxels = 0;     // in the result grid
};

// A narrow-band signed distance field to a swept volume (negative inside),
// clamped to +-band_half_width. Immutable; copies share the grid.
class SweptDistanceField {
 public:
  SweptDistanceField();
  double voxel_size() const;
  double band_half_width() const;
  std::size_t active_voxels() const;

  // Distance at a world point (trilinear between voxel centres), mm.
  double Value(const Vec3& p) const;
  // Value stored at voxel (i,j,k), whose centre is (i,j,k) * voxel_size.
  double ValueAtVoxel(const std::array<int, 3>& ijk) const;
  // Every active voxel with its value, in no particular order.
  struct Voxel {
    std::array<int, 3> ijk;
    float value;
  };
  std::vector<Voxel> ActiveVoxels() const;

  // Triangles of the iso-surface d = iso (mm, |iso| < band - voxel),
  // outward orientation (counter-clockwise seen from outside).
  mesh::TriangleMesh Surface(double iso) const;

  struct Impl;
  explicit SweptDistanceField(std::shared_ptr<const Impl> impl);
  const Impl* impl() const { return impl_.get(); }

 private:
  std::shared_ptr<const Impl> impl_;
};

// Swept distance of a closed triangle mesh B (body coordinates) under the
// poses `poses` (world <- body), taken as the time samples. Throws InputError
// on an empty/non-finite mesh or fewer than 1 pose, and ResourceError when the
// result would exceed options.max_active_voxels. The band is widened to cover
// the largest displacement between consecutive poses.
SweptDistanceField ComputeSweptDistance(const mesh::TriangleMesh& body, const std::vector<Transform>& poses,
                                        const SweptVolumeOptions& options = {}, SweptVolumeSummary* summary = nullptr);

// Same under a motion, with the number of samples chosen from
// options.time_steps and options.max_step_displacement.
SweptDistanceField ComputeSweptDistance(const mesh::TriangleMesh& body, const RigidMotion& motion,
                                        const SweptVolumeOptions& options = {}, SweptVolumeSummary* summary = nullptr);

// Same for a body given as a Solid: its zero iso-surface (Solid::ToMesh) is
// swept. Throws InputError for an empty Solid.
SweptDistanceField ComputeSweptDistance(const geometry::Solid& body, const RigidMotion& motion,
                                        const SweptVolumeOptions& options = {}, SweptVolumeSummary* summary = nullptr);

// The time samples ComputeSweptDistance(body, motion, ...) uses.
std::vector<Transform> SampleMotion(const mesh::TriangleMesh& body, const RigidMotion& motion,
                                    const SweptVolumeOptions& options);
// Same for any pose function t in [0,1] -> Transform (e.g. a relative motion
// f_A^-1 o f_B): at least options.time_steps samples, more until no corner of
// the body's bounding box moves more than max_step_displacement per step
// (measured on a 4096-step probe of the motion).
std::vector<Transform> SamplePoses(const mesh::TriangleMesh& body, const std::function<Transform(double)>& pose,
                                   const SweptVolumeOptions& options);

// Epsilon-offset surface of the swept volume (Reconfigurables: offset(sweep(B, f), eps))
// as a closed triangle mesh.
mesh::TriangleMesh SweptOffsetSurface(const mesh::TriangleMesh& body, const RigidMotion& motion,
                                      const SweptVolumeOptions& options = {});

// The same surface as a geometry::Solid on grid `g` (via geometry::FromMesh),
// for CSG with other Solids.
geometry::Solid SweptOffsetSolid(const geometry::GridSpec& g, const mesh::TriangleMesh& body, const RigidMotion& motion,
                                 const SweptVolumeOptions& options = {});

}  // namespace fabatlas::swept
