// fabatlas/fem/hex_mesh.h — hexahedral meshes for the FEM check.
//
// A HexMesh is a plain list of nodes (mm) and 8-node trilinear (Q1) hexahedra
// in the standard node order (VTK / Abaqus C3D8):
//
//        7-------6          node  (xi, eta, zeta)
//       /|      /|           0    (-1,-1,-1)     4 (-1,-1,+1)
//      4-------5 |           1    (+1,-1,-1)     5 (+1,-1,+1)
//      | 3-----|-2           2    (+1,+1,-1)     6 (+1,+1,+1)
//      |/      |/            3    (-1,+1,-1)     7 (-1,+1,+1)
//      0-------1
//
// so that elements built from axis-aligned boxes have positive Jacobian.
// The FEM check of Fab Forms (sandal heel) meshes the solid as voxel hexes:
// VoxelSolid is a dense occupancy grid that the geometry library fills from
// its level set; this header does not depend on OpenVDB.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fabatlas/vec3.h"

namespace fabatlas::fem {

using fabatlas::Vec2;
using fabatlas::Vec3;

struct HexMesh {
  std::vector<Vec3> nodes;                   // mm
  std::vector<std::array<int, 8>> elements;  // node indices, order above
};

// Dense voxel occupancy grid. Voxel (i,j,k) (0 <= i < dims[0], ...) is the box
// [origin + (i,j,k)*voxel_size, origin + (i+1,j+1,k+1)*voxel_size] (mm), and
// is material iff occupied[i + dims[0]*(j + dims[1]*k)] != 0.
struct VoxelSolid {
  Vec3 origin{0, 0, 0};     // min corner of voxel (0,0,0), mm
  double voxel_size = 1.0;  // edge length, mm, > 0
  std::array<int, 3> dims{0, 0, 0};
  std::vector<uint8_t> occupied;  // size dims[0]*dims[1]*dims[2]

  std::size_t Index(int i, int j, int k) const {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(dims[0]) * (static_cast<std::size_t>(j) + static_cast<std::size_t>(dims[1]) * k);
  }
};

// One hexahedron per occupied voxel; neighbouring voxels share their corner
// nodes (conforming mesh). Only corners of occupied voxels become nodes.
// Elements are ordered by voxel index (i fastest), nodes by lattice index.
// Throws InputError if voxel_size <= 0, a dim is negative, or occupied has the
// wrong size.
HexMesh HexMeshFromVoxels(const VoxelSolid& solid);

// Structured mesh of the planar quadrilateral with corners c0,c1,c2,c3
// (counter-clockwise, xy-plane, mm) mapped bilinearly, nu x nv elements, and
// extruded along z from 0 to thickness in `layers` element layers. Node
// (i,j,k), 0<=i<=nu, 0<=j<=nv, 0<=k<=layers, has index
// i + (nu+1)*(j + (nv+1)*k); edge c0-c1 is j = 0, edge c1-c2 is i = nu.
// Used for plane-strain benchmarks such as Cook's membrane.
HexMesh HexMeshFromQuadPatch(const std::array<Vec2, 4>& corners, int nu, int nv, double thickness, int layers = 1);

// Quadrilateral faces that belong to exactly one element, with node order
// giving an outward normal by the right-hand rule.
std::vector<std::array<int, 4>> BoundaryFaces(const HexMesh& mesh);

}  // namespace fabatlas::fem
