// fabatlas/fem/static_solve.h — static equilibrium of a hyperelastic body.
//
// Total Lagrangian finite elements on 8-node hexahedra with full 2x2x2 Gauss
// integration, compressible Neo-Hookean material (neo_hookean.h). Two
// elements (StaticSolveOptions::element): the trilinear Q1, which locks in
// bending when few elements span a thickness, and the default Q1 with
// incompatible modes (Wilson, Taylor, Doherty & Ghaboussi 1973, in the
// finite-strain form of Simo & Armero 1992: the deformation gradient gets
// three extra, element-internal modes, condensed out per element), which
// does not; docs/fem.md has both papers and the bending validation.
// Equilibrium is the minimiser of the potential energy
//   Pi(u) = sum_e int_Omega_e Psi(F) dV - f_ext . u
// found by Newton's method with a backtracking (Armijo) line search on Pi,
// under load stepping: external forces and prescribed displacements are
// applied in `load_steps` equal increments. Each Newton system is solved by a
// sparse Cholesky factorisation (SuiteSparse CHOLMOD if available at build
// time, otherwise Eigen SimplicialLLT); if the tangent is not positive
// definite (far from equilibrium, or near an instability) it is shifted by a
// multiple of its mean diagonal until it is, which keeps the step a descent
// direction. Loads are dead loads (fixed in the reference configuration).
//
// Units: mm, N, MPa (N/mm^2). Threading: element assembly uses TBB.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "fabatlas/fem/hex_mesh.h"
#include "fabatlas/fem/neo_hookean.h"

namespace fabatlas::fem {

// Displacement component `component` (0=x, 1=y, 2=z) of `node` is prescribed
// to `value` mm (reached at the end of the load stepping).
struct DirichletCondition {
  int node = 0;
  int component = 0;
  double value = 0.0;
};

// Multi-point constraint u_component(node) = factor * u_component(master):
// the dependent DOF is eliminated (master must be neither prescribed nor
// linked). E.g. factor -1 across a mid-plane keeps a solution mirror-symmetric.
struct LinkedComponent {
  int node = 0;
  int master = 0;
  int component = 0;
  double factor = 1.0;
};

struct NodalForce {
  int node = 0;
  Vec3 force{0, 0, 0};  // N
};

// A uniform (dead) traction over a set of quadrilateral faces, given by its
// total force: traction t = total_force / (reference area of the faces), and
// each face contributes the consistent nodal forces t * int N_a dA (2x2 Gauss
// on the bilinear face).
struct FaceTraction {
  std::vector<std::array<int, 4>> faces;  // node indices of each face
  Vec3 total_force{0, 0, 0};              // N
};

struct BoundaryConditions {
  std::vector<DirichletCondition> dirichlet;
  std::vector<LinkedComponent> links;
  std::vector<NodalForce> nodal_forces;
  std::vector<FaceTraction> tractions;

  // Fix all three components of a node at zero displacement.
  void FixNode(int node);
  // Prescribe u_component = 0 at every node of the mesh (e.g. component 2 for
  // plane strain modelled by one layer of hexahedra).
  void FixComponentEverywhere(const HexMesh& mesh, int component);
};

struct StaticSolveOptions {
  // kIncompatibleModes (default): F = I + Grad u + sum_k alpha_k (x) G_k with
  //   the modes phi_k = 1 - xi_k^2 (9 amplitudes per element, condensed out;
  //   Simo & Armero 1992). Bending-locking free; same unknowns and sparsity
  //   as Q1, about 2-3x its element cost.
  // kQ1: plain trilinear displacements (the published Cook's membrane table
  //   of docs/fem.md "Validation" is for this element).
  enum class Element { kIncompatibleModes, kQ1 };
  Element element = Element::kIncompatibleModes;
  int load_steps = 4;              // equal load increments
  int max_newton_iterations = 30;  // per load step (before a cutback)
  int max_cutbacks = 4;            // a failing increment is halved this often
  // A step that converges within this many Newton iterations is quick; after
  // two quick steps in a row a cut-back increment doubles again (never above
  // 1 / load_steps).
  int quick_step_iterations = 6;
  // Each increment is first tried with full Newton steps (halved only while
  // an element would invert), as CalculiX does; if that does not converge in
  // max_newton_iterations, the increment is redone with the Armijo line
  // search on the potential energy, and only then cut back. On slender
  // bending the line search is what costs iterations (the residual of a
  // rotating beam is far from monotone in the energy-decreasing steps), on
  // buckling and snap-through it is what converges. false: line search only.
  bool full_newton_first = true;
  // Converged when ||r_free|| <= relative_tolerance * max(||f_ext,free||,
  // ||reactions to prescribed displacements at the start of the step||).
  double relative_tolerance = 1e-9;
  // Also converged when a full Newton step changes no displacement component
  // by more than step_tolerance * max |u| (the residual is then at its
  // floating-point floor, which can lie above relative_tolerance).
  double step_tolerance = 1e-10;
  double armijo_c = 1e-4;  // sufficient decrease constant
  int max_line_search_halvings = 30;
  bool verbose = false;  // log Newton progress to stderr

  // How each Newton system K d = -r is solved.
  //  kCholesky: sparse direct (CHOLMOD supernodal, else Eigen SimplicialLLT).
  //  kConjugateGradientIncompleteCholesky: Eigen ConjugateGradient
  //    preconditioned by an incomplete Cholesky factor (Eigen
  //    IncompleteCholesky, AMD ordering, zero fill-in beyond K's pattern).
  //  kConjugateGradientJacobi: Eigen ConjugateGradient with the diagonal
  //    (Jacobi) preconditioner.
  // The iterative solves are inexact Newton steps: they stop at
  // ||K d + r|| <= cg_relative_tolerance * ||r||. A step that fails to reach
  // it, or is not a descent direction, is retried with K shifted by a
  // multiple of its mean diagonal, as for the direct solver.
  enum class LinearSolver { kCholesky, kConjugateGradientIncompleteCholesky, kConjugateGradientJacobi };
  LinearSolver linear_solver = LinearSolver::kCholesky;
  double cg_relative_tolerance = 1e-8;
  int cg_max_iterations = 20000;
};

struct StaticSolveSummary {
  bool converged = false;
  std::string message;              // why it stopped if not converged
  int newton_iterations = 0;        // total over all load steps
  int load_steps_taken = 0;         // including cutback sub-steps
  double final_residual_norm = 0;   // N
  std::vector<Vec3> displacements;  // per node, mm (last accepted state)
  double max_displacement = 0;      // max node |u|, mm
  // Largest absolute principal value of the Green-Lagrange strain
  // E = (F^T F - I)/2 over all Gauss points (dimensionless).
  double max_principal_strain = 0;
  int num_free_dofs = 0;
  double assembly_seconds = 0;      // wall time in element assembly
  double linear_solve_seconds = 0;  // wall time in factorisation + solves
  long long linear_iterations = 0;  // conjugate-gradient iterations (iterative solvers only)
  int factorizations = 0;           // linear-solver set-ups, shifted retries included
  double total_seconds = 0;
};

// Solves for static equilibrium. Bad input (empty mesh, node index out of
// range, inverted element, non-positive material) throws InputError;
// non-convergence is reported in the summary (converged = false) with the last
// accepted state, never thrown.
StaticSolveSummary SolveStatic(const HexMesh& mesh, const Material& material, const BoundaryConditions& bc,
                               const StaticSolveOptions& options = {});

}  // namespace fabatlas::fem
