// The voxel cantilever of the FEM tests (bending_test.cc,
// static_solve_test.cc): a beam along x of length L and square section h x h
// meshed with cubic voxels, its end face x = 0 clamped (every node fixed)
// and a dead traction of total force (0, 0, -P) spread over its end face
// x = L.
#pragma once

#include <vector>

#include "fabatlas/fem/hex_mesh.h"
#include "fabatlas/fem/static_solve.h"

namespace fabatlas::fem {

struct Cantilever {
  double length = 0;
  HexMesh mesh;
  BoundaryConditions bc;
  std::vector<int> end_nodes;  // the nodes of the loaded end face

  // Mean vertical deflection of the end face (downwards positive), mm.
  double TipDeflection(const StaticSolveSummary& r) const {
    double uz = 0;
    for (int n : end_nodes) uz += r.displacements[n][2];
    return -uz / static_cast<double>(end_nodes.size());
  }
};

// L and h in mm, multiples of `voxel`; P in N.
inline Cantilever MakeCantilever(double L, double h, double voxel, double P) {
  Cantilever c;
  c.length = L;
  VoxelSolid v;
  v.voxel_size = voxel;
  v.dims = {static_cast<int>(L / voxel), static_cast<int>(h / voxel), static_cast<int>(h / voxel)};
  v.occupied.assign(static_cast<std::size_t>(v.dims[0]) * v.dims[1] * v.dims[2], 1);
  c.mesh = HexMeshFromVoxels(v);
  FaceTraction tip;
  tip.total_force = {0, 0, -P};
  for (const auto& f : BoundaryFaces(c.mesh)) {
    bool on_end = true;
    for (int a : f) on_end = on_end && c.mesh.nodes[a][0] == L;
    if (on_end) tip.faces.push_back(f);
  }
  c.bc.tractions.push_back(tip);
  for (int n = 0; n < static_cast<int>(c.mesh.nodes.size()); ++n) {
    if (c.mesh.nodes[n][0] == 0.0) c.bc.FixNode(n);
    if (c.mesh.nodes[n][0] == L) c.end_nodes.push_back(n);
  }
  return c;
}

}  // namespace fabatlas::fem
