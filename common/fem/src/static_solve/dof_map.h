// static_solve/dof_map.h (internal to fabatlas_fem) — the unknowns of a
// static solve: which mesh DOFs are prescribed, which are free and in what
// order, which are linked to another; and the external load.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "fabatlas/fem/hex_mesh.h"
#include "fabatlas/fem/static_solve.h"

namespace fabatlas::fem::internal {

// Mesh DOF k (3 per node: x, y, z) is unknown free_index[k] times
// coefficient[k], or prescribed (free_index[k] < 0) to the load factor
// times prescribed[k].
struct DofMap {
  std::vector<int> free_index;
  std::vector<double> coefficient;
  Eigen::VectorXd prescribed;
  int num_free = 0;

  // The unknowns' share of a vector over all mesh DOFs: sum over the mesh
  // DOFs of coefficient * full, per unknown.
  Eigen::VectorXd Restrict(const Eigen::VectorXd& full) const;
  // Sets every prescribed DOF of u to load_factor times its value.
  void Prescribe(double load_factor, Eigen::VectorXd& u) const;
  // A vector over the unknowns as the mesh DOFs it moves (0 where prescribed).
  void Spread(const Eigen::VectorXd& d, Eigen::VectorXd& full) const;
};

// The DOF map of bc on mesh: free unknowns numbered node by node in
// nested-dissection order (nested_dissection.h), links resolved to their
// master's unknown. Throws InputError naming a bad condition, or when every
// DOF is prescribed.
DofMap NumberDofs(const HexMesh& mesh, const BoundaryConditions& bc);

// The full external load on every mesh DOF (N): nodal forces and face
// tractions. Throws InputError for a node out of range or a bad face set.
Eigen::VectorXd TotalLoad(const HexMesh& mesh, const BoundaryConditions& bc);

}  // namespace fabatlas::fem::internal
