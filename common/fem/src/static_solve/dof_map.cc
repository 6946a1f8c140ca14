// The unknowns and the load of a static solve (static_solve/dof_map.h).
#include "dof_map.h"

#include <array>
#include <cmath>
#include <string>

#include <Eigen/Geometry>

#include "fabatlas/error.h"
#include "fabatlas/fem/nested_dissection.h"
#include "gauss_points.h"

namespace fabatlas::fem::internal {

namespace {

// Consistent nodal forces of a uniform traction with the given total force.
void AddFaceTraction(const HexMesh& mesh, const FaceTraction& t, Eigen::VectorXd* f) {
  if (t.faces.empty()) throw InputError("face traction: empty face set");
  const int n = static_cast<int>(mesh.nodes.size());
  // int N_a dA per face node, 2x2 Gauss on the bilinear quad.
  std::vector<std::array<double, 4>> weights(t.faces.size());
  double area = 0;
  static constexpr double kS[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  for (std::size_t fi = 0; fi < t.faces.size(); ++fi) {
    const auto& face = t.faces[fi];
    for (int a : face) {
      if (a < 0 || a >= n) throw InputError("face traction: node index " + std::to_string(a) + " out of range");
    }
    weights[fi] = {0, 0, 0, 0};
    for (int g = 0; g < 4; ++g) {
      const double s = kS[g][0] * kGauss, r = kS[g][1] * kGauss;
      Eigen::Vector3d xs = Eigen::Vector3d::Zero(), xr = Eigen::Vector3d::Zero();
      double N[4];
      for (int a = 0; a < 4; ++a) {
        N[a] = 0.25 * (1 + kS[a][0] * s) * (1 + kS[a][1] * r);
        const Eigen::Vector3d X(mesh.nodes[face[a]][0], mesh.nodes[face[a]][1], mesh.nodes[face[a]][2]);
        xs += 0.25 * kS[a][0] * (1 + kS[a][1] * r) * X;
        xr += 0.25 * kS[a][1] * (1 + kS[a][0] * s) * X;
      }
      const double dA = xs.cross(xr).norm();
      for (int a = 0; a < 4; ++a) weights[fi][a] += N[a] * dA;
      area += dA;
    }
  }
  if (!(area > 0)) throw InputError("face traction: faces have zero area");
  for (std::size_t fi = 0; fi < t.faces.size(); ++fi)
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i) (*f)[3 * t.faces[fi][a] + i] += t.total_force[i] / area * weights[fi][a];
}

}  // namespace

Eigen::VectorXd DofMap::Restrict(const Eigen::VectorXd& full) const {
  Eigen::VectorXd r = Eigen::VectorXd::Zero(num_free);
  for (std::size_t k = 0; k < free_index.size(); ++k)
    if (free_index[k] >= 0) r[free_index[k]] += coefficient[k] * full[static_cast<Eigen::Index>(k)];
  return r;
}

void DofMap::Prescribe(double load_factor, Eigen::VectorXd& u) const {
  for (std::size_t k = 0; k < free_index.size(); ++k)
    if (free_index[k] < 0) u[static_cast<Eigen::Index>(k)] = load_factor * prescribed[static_cast<Eigen::Index>(k)];
}

void DofMap::Spread(const Eigen::VectorXd& d, Eigen::VectorXd& full) const {
  full.setZero();
  for (std::size_t k = 0; k < free_index.size(); ++k) {
    const int fk = free_index[k];
    if (fk >= 0) full[static_cast<Eigen::Index>(k)] = coefficient[k] * d[fk];
  }
}

DofMap NumberDofs(const HexMesh& mesh, const BoundaryConditions& bc) {
  const int nn = static_cast<int>(mesh.nodes.size());
  const std::size_t ndof = 3 * static_cast<std::size_t>(nn);
  DofMap dofs;
  std::vector<int>& free_index = dofs.free_index;
  free_index.assign(ndof, 0);
  dofs.prescribed = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(ndof));
  for (const auto& d : bc.dirichlet) {
    if (d.node < 0 || d.node >= nn || d.component < 0 || d.component > 2 || !std::isfinite(d.value)) {
      throw InputError("dirichlet condition: node " + std::to_string(d.node) + " component " +
                       std::to_string(d.component) + " is invalid");
    }
    free_index[3 * d.node + d.component] = -1;
    dofs.prescribed[3 * d.node + d.component] = d.value;
  }
  dofs.coefficient.assign(ndof, 1.0);
  for (const auto& l : bc.links) {
    if (l.node < 0 || l.node >= nn || l.master < 0 || l.master >= nn || l.component < 0 || l.component > 2 ||
        l.node == l.master || !std::isfinite(l.factor)) {
      throw InputError("linked component: node " + std::to_string(l.node) + " master " + std::to_string(l.master) +
                       " is invalid");
    }
    const std::size_t k = 3 * static_cast<std::size_t>(l.node) + l.component;
    if (free_index[k] != 0)
      throw InputError("linked component: node " + std::to_string(l.node) + " is also prescribed or linked twice");
    free_index[k] = -2;  // resolved below
  }
  // Free unknowns numbered node by node in nested-dissection order
  // (nested_dissection.h): the factorisation keeps that order
  // (tangent_solve.h), so its fill, its roundings and every FEM result
  // depend on the mesh alone.
  int& num_free = dofs.num_free;
  for (int n : NestedDissectionOrder(mesh))
    for (int c = 0; c < 3; ++c)
      if (free_index[3 * static_cast<std::size_t>(n) + c] == 0)
        free_index[3 * static_cast<std::size_t>(n) + c] = num_free++;
  for (const auto& l : bc.links) {
    const std::size_t k = 3 * static_cast<std::size_t>(l.node) + l.component;
    const std::size_t m = 3 * static_cast<std::size_t>(l.master) + l.component;
    if (free_index[m] < 0) {
      throw InputError("linked component: master node " + std::to_string(l.master) + " must be free");
    }
    free_index[k] = free_index[m];
    dofs.coefficient[k] = l.factor;
  }
  if (num_free == 0) throw InputError("static solve: every degree of freedom is prescribed");
  return dofs;
}

Eigen::VectorXd TotalLoad(const HexMesh& mesh, const BoundaryConditions& bc) {
  const int nn = static_cast<int>(mesh.nodes.size());
  Eigen::VectorXd f_total = Eigen::VectorXd::Zero(3 * static_cast<Eigen::Index>(nn));
  for (const auto& nf : bc.nodal_forces) {
    if (nf.node < 0 || nf.node >= nn)
      throw InputError("nodal force: node " + std::to_string(nf.node) + " out of range");
    for (int i = 0; i < 3; ++i) f_total[3 * nf.node + i] += nf.force[i];
  }
  for (const auto& t : bc.tractions) AddFaceTraction(mesh, t, &f_total);
  return f_total;
}

}  // namespace fabatlas::fem::internal
