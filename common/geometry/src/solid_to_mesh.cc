// solid_to_mesh.cc — Solid::ToMesh: a level set's surface as triangles with
// OpenVDB's volumeToMesh.
//
// volumeToMesh for FloatGrid is one of the templates libopenvdb instantiates
// itself (OPENVDB_USE_EXPLICIT_INSTANTIATION: VolumeToMesh.h declares it
// extern), so this file compiles in seconds; driving the VolumeToMesh class
// directly would instantiate the whole mesher here (minutes of compile time).
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "solid_impl.h"

namespace fabatlas::geometry {

mesh::TriangleMesh Solid::ToMesh(double adaptivity) const {
  mesh::TriangleMesh out;
  if (!impl_) return out;
  if (impl_->boundary) return *impl_->boundary;
  if (!std::isfinite(adaptivity) || adaptivity < 0 || adaptivity > 1) {
    throw InputError("Solid::ToMesh: adaptivity must be in [0,1]");
  }
  // Iso-value a hair above 0 (1e-4 voxel): voxels lying exactly on the surface
  // (faces of boxes at round sizes fall on voxel centres) then count as
  // inside, which avoids a chamfer of up to a voxel along such edges.
  // relaxDisorientedTriangles = true, the mesher's default.
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(*impl_->Grid(), points, triangles, quads, kMeshIso * impl_->spec.voxel_size, adaptivity,
                               /*relaxDisorientedTriangles=*/true);
  // Every quad as two triangles, then the triangles, in volumeToMesh's order.
  // volumeToMesh orients its polygons clockwise seen from outside for a level
  // set (negative inside); reverse them to the outward (counter-clockwise)
  // convention of TriangleMesh. In parallel, so the result is the same for
  // any thread count.
  const std::size_t np = points.size(), nquads = quads.size(), ntriangles = triangles.size();
  out.vertices.resize(np);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, np, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) out.vertices[i] = {points[i].x(), points[i].y(), points[i].z()};
  });
  out.triangles.resize(2 * nquads + ntriangles);
  auto idx = [](openvdb::Index32 i) { return static_cast<std::int32_t>(i); };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nquads, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const openvdb::Vec4I& q = quads[i];
      out.triangles[2 * i] = {idx(q[0]), idx(q[2]), idx(q[1])};
      out.triangles[2 * i + 1] = {idx(q[0]), idx(q[3]), idx(q[2])};
    }
  });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ntriangles, 4096),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const openvdb::Vec3I& t = triangles[i];
                        out.triangles[2 * nquads + i] = {idx(t[0]), idx(t[2]), idx(t[1])};
                      }
                    });
  return out;
}

}  // namespace fabatlas::geometry
