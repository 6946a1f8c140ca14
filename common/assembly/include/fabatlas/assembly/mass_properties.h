// fabatlas/assembly/mass_properties.h — mass and centre of mass of a part mesh.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace fabatlas::assembly {

struct MassProperties {
  double volume_mm3 = 0;                                     // signed-tetrahedra volume
  Eigen::Vector3d centre_of_mass = Eigen::Vector3d::Zero();  // mm, mesh frame
  Eigen::Vector3d bbox_min = Eigen::Vector3d::Zero();
  Eigen::Vector3d bbox_max = Eigen::Vector3d::Zero();
  int triangles = 0;
};

// A part mesh as read: vertices (mm, mesh frame) and triangles (polygons fanned).
struct PartMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 3>> triangles;
};

// Reads an OBJ, OFF or STL (ASCII or binary) mesh. Throws InputError("path: ...")
// for unreadable or malformed files.
PartMesh ReadPartMesh(const std::string& path);

// Reads an OBJ, OFF or STL (ASCII or binary) triangle/polygon mesh (mm) and
// integrates volume and centre of mass over signed tetrahedra from the origin
// (exact for closed, consistently oriented meshes; the FabHacks meshes are not
// all watertight, so |volume| is used and a near-zero volume falls back to the
// bounding-box centre). Mass = volume × density 1 (EXAMPLES.md).
// Remembered per path for the process lifetime (parts share meshes).
// Throws InputError("path: ...") for unreadable or malformed files.
MassProperties ComputeMassProperties(const std::string& path);

}  // namespace fabatlas::assembly
