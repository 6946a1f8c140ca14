// static_solve/problem.h (internal to fabatlas_fem) — the discrete problem of
// a static solve: element forces and tangents (Neo-Hookean, Q1 or
// incompatible modes with static condensation), their assembly into the
// free-free tangent, energies and strains.
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Sparse>

#include "fabatlas/fem/hex_mesh.h"
#include "fabatlas/fem/neo_hookean.h"
#include "gauss_points.h"

namespace fabatlas::fem::internal {

using SpMat = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

// The discrete problem: mesh, Gauss data, DOF map, sparsity pattern, and for
// the incompatible-mode element the per-element static condensation of the
// mode amplitudes alpha (Simo & Armero 1992, Sec. 5: the element equations
// [K_uu K_ua; K_au K_aa] [du; da] = -[r_u; r_a] are reduced to
// (K_uu - K_ua K_aa^-1 K_au) du = -(r_u - K_ua K_aa^-1 r_a) and
// da = -K_aa^-1 (r_a + K_au du)).
class Problem {
 public:
  // free_index / coefficient: per mesh DOF, its unknown (< 0: prescribed)
  // and the factor it enters with (dof_map.h).
  Problem(const HexMesh& mesh, const Material& mat, std::vector<GaussPoint> gps, std::vector<int> free_index,
          std::vector<double> coefficient, int num_free, bool incompatible);

  int num_free() const { return num_free_; }
  // Number of incompatible-mode unknowns (9 per element, 0 for Q1).
  Eigen::Index num_alpha() const { return incompatible_ ? static_cast<Eigen::Index>(9 * mesh_.elements.size()) : 0; }
  SpMat& K() { return K_; }
  const std::vector<int>& diagonal_slots() const { return diag_; }

  // Strain energy sum_e int Psi dV (mJ); +inf if any Gauss point has J <= 0.
  // Summed in a fixed order (deterministic reduce: the same split and join
  // tree whatever the thread count or scheduling), so a sample's FEM measures
  // are the same bits in process and on any worker.
  double StrainEnergy(const Eigen::VectorXd& u, const Eigen::VectorXd& alpha) const;

  // Internal forces f_int = dW/du (all DOFs). With want_K also the
  // (condensed) free-free tangent into K(), the condensed internal forces
  // into *f_cond (all DOFs) and the condensation data AlphaIncrement uses.
  // Returns |dW/dalpha|^2 (0 for Q1).
  double Assemble(const Eigen::VectorXd& u, const Eigen::VectorXd& alpha, Eigen::VectorXd* f_int,
                  Eigen::VectorXd* f_cond, bool want_K);

  // The mode increments da_e = -K_aa^-1 (r_a + K_au du_e) for a displacement
  // increment du (all DOFs), from the last Assemble with want_K; and
  // dW/dalpha . da.
  double AlphaIncrement(const Eigen::VectorXd& du, Eigen::VectorXd* dalpha) const;

  // Largest |principal Green-Lagrange strain| over all Gauss points.
  double MaxPrincipalStrain(const Eigen::VectorXd& u, const Eigen::VectorXd& alpha) const;

 private:
  void ElementKernel(std::size_t e, const Eigen::VectorXd& u, const Eigen::VectorXd& alpha, double* fe, double* fc,
                     double* ke);
  void Condense(std::size_t e, const double* f, const double* k33, double* fc, double* ke);
  void Scatter(std::size_t e, const double* fe, const double* fc, const double* ke, Eigen::VectorXd* f_int,
               Eigen::VectorXd* f_cond);
  void BuildPattern();

  const HexMesh& mesh_;
  Material mat_;
  std::vector<GaussPoint> gps_;
  std::vector<int> free_;
  std::vector<double> coef_;
  int num_free_;
  bool incompatible_;
  SpMat K_;
  std::vector<int> diag_;
  std::vector<double> ke_, fe_, fc_;
  // Per element, from the last Assemble with the tangent: K_aa^-1 K_au
  // (9 x 24, column-major), K_aa^-1 r_a (9), and r_a = dW/dalpha (9).
  std::vector<double> cond_M_, cond_m_, f_alpha_;
};

}  // namespace fabatlas::fem::internal
