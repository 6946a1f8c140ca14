// Total Lagrangian Q1 hexahedra, Neo-Hookean, Newton + line search + load
// stepping. See static_solve.h for the method and docs/fem.md.
#include "fabatlas/fem/static_solve.h"

#include <algorithm>
#include <chrono>
#include <functional>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include <Eigen/Dense>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Sparse>
#ifdef FABATLAS_FEM_HAVE_CHOLMOD
#include <Eigen/CholmodSupport>
#endif
#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "fabatlas/error.h"
#include "fabatlas/fem/nested_dissection.h"

namespace fabatlas::fem {

void BoundaryConditions::FixNode(int node) {
  for (int c = 0; c < 3; ++c) dirichlet.push_back({node, c, 0.0});
}

void BoundaryConditions::FixComponentEverywhere(const HexMesh& mesh, int component) {
  for (int n = 0; n < static_cast<int>(mesh.nodes.size()); ++n) {
    dirichlet.push_back({n, component, 0.0});
  }
}

namespace {

using Clock = std::chrono::steady_clock;
using SpMat = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
#ifdef FABATLAS_FEM_HAVE_CHOLMOD
using Cholesky = Eigen::CholmodSupernodalLLT<SpMat, Eigen::Lower>;
#else
using Cholesky = Eigen::SimplicialLLT<SpMat, Eigen::Lower, Eigen::AMDOrdering<int>>;
#endif

double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

constexpr double kGauss = 0.57735026918962576451;  // 1/sqrt(3)
constexpr int kNodeSign[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                 {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};

// Reference-configuration data of one Gauss point: dN_a/dX, weight*det J, and
// the gradients G_k = dphi_k/dX of the three incompatible modes
// phi_k = 1 - xi_k^2 (Wilson, Taylor, Doherty & Ghaboussi 1973), taken as
// Simo & Armero 1992, Eq. (4.9) do: G_k = (j0/j) J0^-T grad_xi phi_k with the
// Jacobian J0 = dX/dxi at the element centre, so that int G_k dV = 0 (the
// patch test) on any hexahedron.
struct GaussPoint {
  double dN[8][3];
  double G[3][3];  // G[k][J] = d phi_k / d X_J (scaled as above)
  double weight;
};

// Full 2x2x2 Gauss integration of the trilinear hexahedron.
std::vector<GaussPoint> PrecomputeGaussPoints(const HexMesh& mesh) {
  std::vector<GaussPoint> gps(mesh.elements.size() * 8);
  for (std::size_t e = 0; e < mesh.elements.size(); ++e) {
    const auto& el = mesh.elements[e];
    Eigen::Matrix3d Jc = Eigen::Matrix3d::Zero();  // dX/dxi at the centre
    for (int a = 0; a < 8; ++a)
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) Jc(i, j) += 0.125 * mesh.nodes[el[a]][i] * kNodeSign[a][j];
    const double j0 = Jc.determinant();
    const Eigen::Matrix3d Jc_inv = j0 > 0 ? Eigen::Matrix3d(Jc.inverse()) : Eigen::Matrix3d::Zero();
    for (int g = 0; g < 8; ++g) {
      const double xi[3] = {kNodeSign[g][0] * kGauss, kNodeSign[g][1] * kGauss,
                            kNodeSign[g][2] * kGauss};
      double dNdxi[8][3];
      for (int a = 0; a < 8; ++a) {
        const double s[3] = {1 + kNodeSign[a][0] * xi[0], 1 + kNodeSign[a][1] * xi[1],
                             1 + kNodeSign[a][2] * xi[2]};
        dNdxi[a][0] = 0.125 * kNodeSign[a][0] * s[1] * s[2];
        dNdxi[a][1] = 0.125 * kNodeSign[a][1] * s[0] * s[2];
        dNdxi[a][2] = 0.125 * kNodeSign[a][2] * s[0] * s[1];
      }
      Eigen::Matrix3d J0 = Eigen::Matrix3d::Zero();  // dX_i/dxi_j
      for (int a = 0; a < 8; ++a)
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) J0(i, j) += mesh.nodes[el[a]][i] * dNdxi[a][j];
      const double det = J0.determinant();
      if (!(det > 0)) {
        throw InputError("hex mesh: element " + std::to_string(e) +
                         " is inverted or degenerate (det J = " + std::to_string(det) +
                         "); check the node order");
      }
      const Eigen::Matrix3d Jinv = J0.inverse();
      GaussPoint& gp = gps[e * 8 + g];
      gp.weight = det;  // Gauss weights are 1
      for (int a = 0; a < 8; ++a)
        for (int j = 0; j < 3; ++j) {
          gp.dN[a][j] = dNdxi[a][0] * Jinv(0, j) + dNdxi[a][1] * Jinv(1, j) + dNdxi[a][2] * Jinv(2, j);
        }
      // d phi_k / d xi_m = -2 xi_k delta_km.
      for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 3; ++j) gp.G[k][j] = (j0 / det) * (-2.0 * xi[k]) * Jc_inv(k, j);
    }
  }
  return gps;
}

// F = I + sum_a u_a (x) dN_a + sum_k alpha_k (x) G_k. `alpha` points at the
// element's 9 incompatible-mode amplitudes (alpha[3k + i]: component i of
// mode k, mm), or is null for plain Q1.
Mat3 DeformationGradient(const GaussPoint& gp, const std::array<int, 8>& el,
                         const Eigen::VectorXd& u, const double* alpha) {
  Mat3 F{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  for (int a = 0; a < 8; ++a) {
    const double* ua = u.data() + 3 * static_cast<std::size_t>(el[a]);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) F[i][j] += ua[i] * gp.dN[a][j];
  }
  if (alpha) {
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) F[i][j] += alpha[3 * k + i] * gp.G[k][j];
  }
  return F;
}

// The discrete problem: mesh, Gauss data, DOF map, sparsity pattern, and for
// the incompatible-mode element the per-element static condensation of the
// mode amplitudes alpha (Simo & Armero 1992, Sec. 5: the element equations
// [K_uu K_ua; K_au K_aa] [du; da] = -[r_u; r_a] are reduced to
// (K_uu - K_ua K_aa^-1 K_au) du = -(r_u - K_ua K_aa^-1 r_a) and
// da = -K_aa^-1 (r_a + K_au du)).
class Problem {
 public:
  Problem(const HexMesh& mesh, const Material& mat, std::vector<GaussPoint> gps,
          std::vector<int> free_index, std::vector<double> coefficient, int num_free, bool incompatible)
      : mesh_(mesh), mat_(mat), gps_(std::move(gps)), free_(std::move(free_index)),
        coef_(std::move(coefficient)), num_free_(num_free), incompatible_(incompatible) {
    BuildPattern();
    if (incompatible_) {
      const std::size_t ne = mesh_.elements.size();
      cond_M_.assign(ne * 216, 0.0);
      cond_m_.assign(ne * 9, 0.0);
      f_alpha_.assign(ne * 9, 0.0);
    }
  }

  int num_free() const { return num_free_; }
  // Number of incompatible-mode unknowns (9 per element, 0 for Q1).
  Eigen::Index num_alpha() const { return incompatible_ ? static_cast<Eigen::Index>(9 * mesh_.elements.size()) : 0; }
  SpMat& K() { return K_; }
  const std::vector<int>& diagonal_slots() const { return diag_; }

  // Strain energy sum_e int Psi dV (mJ); +inf if any Gauss point has J <= 0.
  // Summed in a fixed order (deterministic reduce: the same split and join
  // tree whatever the thread count or scheduling), so a sample's FEM measures
  // are the same bits in process and on any worker.
  double StrainEnergy(const Eigen::VectorXd& u, const Eigen::VectorXd& alpha) const {
    const std::size_t ne = mesh_.elements.size();
    return tbb::parallel_deterministic_reduce(
        tbb::blocked_range<std::size_t>(0, ne, 256), 0.0,
        [&](const tbb::blocked_range<std::size_t>& r, double acc) {
          for (std::size_t e = r.begin(); e < r.end(); ++e) {
            const double* a = incompatible_ ? alpha.data() + 9 * e : nullptr;
            for (int g = 0; g < 8; ++g) {
              const GaussPoint& gp = gps_[e * 8 + g];
              acc += gp.weight * NeoHookeanEnergy(mat_, DeformationGradient(gp, mesh_.elements[e], u, a));
            }
          }
          return acc;
        },
        std::plus<double>());
  }

  // Internal forces f_int = dW/du (all DOFs). With want_K also the
  // (condensed) free-free tangent into K(), the condensed internal forces
  // into *f_cond (all DOFs) and the condensation data AlphaIncrement uses.
  // Returns |dW/dalpha|^2 (0 for Q1).
  double Assemble(const Eigen::VectorXd& u, const Eigen::VectorXd& alpha, Eigen::VectorXd* f_int,
                  Eigen::VectorXd* f_cond, bool want_K) {
    const std::size_t ne = mesh_.elements.size();
    f_int->setZero(u.size());
    if (want_K) {
      f_cond->setZero(u.size());
      std::fill(K_.valuePtr(), K_.valuePtr() + K_.nonZeros(), 0.0);
    }
    constexpr std::size_t kBatch = 2048;
    ke_.resize(kBatch * 576);
    fe_.resize(kBatch * 24);
    fc_.resize(kBatch * 24);
    for (std::size_t b0 = 0; b0 < ne; b0 += kBatch) {
      const std::size_t b1 = std::min(ne, b0 + kBatch);
      tbb::parallel_for(tbb::blocked_range<std::size_t>(b0, b1, 64),
                        [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t e = r.begin(); e < r.end(); ++e) {
                            ElementKernel(e, u, alpha, &fe_[(e - b0) * 24], &fc_[(e - b0) * 24],
                                          want_K ? &ke_[(e - b0) * 576] : nullptr);
                          }
                        });
      for (std::size_t e = b0; e < b1; ++e) {
        Scatter(e, &fe_[(e - b0) * 24], want_K ? &fc_[(e - b0) * 24] : nullptr,
                want_K ? &ke_[(e - b0) * 576] : nullptr, f_int, f_cond);
      }
    }
    double fa2 = 0;
    for (double v : f_alpha_) fa2 += v * v;
    return fa2;
  }

  // The mode increments da_e = -K_aa^-1 (r_a + K_au du_e) for a displacement
  // increment du (all DOFs), from the last Assemble with want_K; and
  // dW/dalpha . da.
  double AlphaIncrement(const Eigen::VectorXd& du, Eigen::VectorXd* dalpha) const {
    dalpha->setZero(num_alpha());
    if (!incompatible_) return 0.0;
    const std::size_t ne = mesh_.elements.size();
    double dot = 0;
    for (std::size_t e = 0; e < ne; ++e) {
      const auto& el = mesh_.elements[e];
      double due[24];
      for (int a = 0; a < 8; ++a)
        for (int i = 0; i < 3; ++i) due[3 * a + i] = du[3 * static_cast<Eigen::Index>(el[a]) + i];
      const double* M = &cond_M_[e * 216];
      for (int j = 0; j < 9; ++j) {
        double v = cond_m_[e * 9 + j];
        for (int c = 0; c < 24; ++c) v += M[c * 9 + j] * due[c];
        (*dalpha)[static_cast<Eigen::Index>(9 * e + j)] = -v;
        dot += f_alpha_[e * 9 + j] * -v;
      }
    }
    return dot;
  }

  // Largest |principal Green-Lagrange strain| over all Gauss points.
  double MaxPrincipalStrain(const Eigen::VectorXd& u, const Eigen::VectorXd& alpha) const {
    const std::size_t ne = mesh_.elements.size();
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, ne, 256), 0.0,
        [&](const tbb::blocked_range<std::size_t>& r, double acc) {
          for (std::size_t e = r.begin(); e < r.end(); ++e) {
            const double* a = incompatible_ ? alpha.data() + 9 * e : nullptr;
            for (int g = 0; g < 8; ++g) {
              const Mat3 F = DeformationGradient(gps_[e * 8 + g], mesh_.elements[e], u, a);
              Eigen::Matrix3d Fm;
              for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) Fm(i, j) = F[i][j];
              const Eigen::Matrix3d E = 0.5 * (Fm.transpose() * Fm - Eigen::Matrix3d::Identity());
              Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
              es.computeDirect(E, Eigen::EigenvaluesOnly);
              acc = std::max(acc, es.eigenvalues().cwiseAbs().maxCoeff());
            }
          }
          return acc;
        },
        [](double a, double b) { return std::max(a, b); });
  }

 private:
  // Element forces fe (24, dW/du) and, if ke, the tangent (24 x 24) and the
  // condensed forces fc (24). The incompatible-mode element treats its three
  // modes as three extra "nodes" with gradients G_k (33 unknowns), then
  // condenses them out.
  void ElementKernel(std::size_t e, const Eigen::VectorXd& u, const Eigen::VectorXd& alpha, double* fe,
                     double* fc, double* ke) {
    const auto& el = mesh_.elements[e];
    const int na = incompatible_ ? 11 : 8;
    const int n3 = 3 * na;
    const double* al = incompatible_ ? alpha.data() + 9 * e : nullptr;
    double f[33] = {0};
    double k33[33 * 33];
    if (ke) std::fill(k33, k33 + n3 * n3, 0.0);
    for (int g = 0; g < 8; ++g) {
      const GaussPoint& gp = gps_[e * 8 + g];
      double grad[11][3];
      for (int a = 0; a < 8; ++a)
        for (int j = 0; j < 3; ++j) grad[a][j] = gp.dN[a][j];
      if (incompatible_)
        for (int k = 0; k < 3; ++k)
          for (int j = 0; j < 3; ++j) grad[8 + k][j] = gp.G[k][j];
      const Mat3 F = DeformationGradient(gp, el, u, al);
      const Mat3 P = NeoHookeanStress(mat_, F);
      for (int a = 0; a < na; ++a)
        for (int i = 0; i < 3; ++i) {
          f[3 * a + i] += gp.weight * (P[i][0] * grad[a][0] + P[i][1] * grad[a][1] + P[i][2] * grad[a][2]);
        }
      if (!ke) continue;
      const Tangent9 A = NeoHookeanTangent(mat_, F);
      // T[a][i][kL] = sum_J grad_a,J A[iJ][kL]
      double T[11][3][9];
      for (int a = 0; a < na; ++a)
        for (int i = 0; i < 3; ++i)
          for (int kl = 0; kl < 9; ++kl) {
            T[a][i][kl] = grad[a][0] * A[3 * i][kl] + grad[a][1] * A[3 * i + 1][kl] + grad[a][2] * A[3 * i + 2][kl];
          }
      for (int a = 0; a < na; ++a)
        for (int i = 0; i < 3; ++i) {
          double* row = k33 + (3 * a + i) * n3;
          for (int b = 0; b < na; ++b)
            for (int k = 0; k < 3; ++k) {
              row[3 * b + k] += gp.weight * (T[a][i][3 * k] * grad[b][0] + T[a][i][3 * k + 1] * grad[b][1] +
                                             T[a][i][3 * k + 2] * grad[b][2]);
            }
        }
    }
    std::copy(f, f + 24, fe);
    if (!incompatible_) {
      if (ke) {
        std::copy(k33, k33 + 576, ke);
        std::copy(f, f + 24, fc);
      }
      return;
    }
    std::copy(f + 24, f + 33, &f_alpha_[e * 9]);
    if (!ke) return;
    // Static condensation. K_aa is shifted until positive definite (like
    // the global tangent), which keeps the step a descent direction.
    Eigen::Matrix<double, 9, 9> Kaa;
    Eigen::Matrix<double, 9, 24> Kau;
    Eigen::Matrix<double, 9, 1> fa;
    for (int j = 0; j < 9; ++j) {
      fa[j] = f[24 + j];
      for (int c = 0; c < 9; ++c) Kaa(j, c) = k33[(24 + j) * 33 + 24 + c];
      for (int c = 0; c < 24; ++c) Kau(j, c) = k33[(24 + j) * 33 + c];
    }
    Eigen::LLT<Eigen::Matrix<double, 9, 9>> llt(Kaa);
    const double mean_diag = Kaa.diagonal().cwiseAbs().mean();
    for (double shift = 1e-8 * mean_diag; llt.info() != Eigen::Success && shift < 1e8 * mean_diag; shift *= 10) {
      llt.compute(Kaa + shift * Eigen::Matrix<double, 9, 9>::Identity());
    }
    const Eigen::Matrix<double, 9, 24> M = llt.solve(Kau);
    const Eigen::Matrix<double, 9, 1> m = llt.solve(fa);
    std::copy(M.data(), M.data() + 216, &cond_M_[e * 216]);  // column-major 9 x 24
    std::copy(m.data(), m.data() + 9, &cond_m_[e * 9]);
    for (int r = 0; r < 24; ++r) {
      double v = f[r];
      for (int j = 0; j < 9; ++j) v -= k33[r * 33 + 24 + j] * m[j];
      fc[r] = v;
      for (int c = 0; c < 24; ++c) {
        double w = k33[r * 33 + c];
        for (int j = 0; j < 9; ++j) w -= k33[r * 33 + 24 + j] * M(j, c);
        ke[r * 24 + c] = w;
      }
    }
  }

  void Scatter(std::size_t e, const double* fe, const double* fc, const double* ke, Eigen::VectorXd* f_int,
               Eigen::VectorXd* f_cond) {
    const auto& el = mesh_.elements[e];
    int g[24];
    double w[24];
    for (int a = 0; a < 8; ++a)
      for (int i = 0; i < 3; ++i) {
        (*f_int)[3 * el[a] + i] += fe[3 * a + i];
        if (fc) (*f_cond)[3 * el[a] + i] += fc[3 * a + i];
        g[3 * a + i] = free_[3 * static_cast<std::size_t>(el[a]) + i];
        w[3 * a + i] = coef_[3 * static_cast<std::size_t>(el[a]) + i];
      }
    if (!ke) return;
    const int* outer = K_.outerIndexPtr();
    const int* inner = K_.innerIndexPtr();
    double* val = K_.valuePtr();
    for (int c = 0; c < 24; ++c) {
      const int col = g[c];
      if (col < 0) continue;
      const int* begin = inner + outer[col];
      const int* end = inner + outer[col + 1];
      for (int r = 0; r < 24; ++r) {
        const int row = g[r];
        if (row < 0) continue;
        const int* p = std::lower_bound(begin, end, row);
        val[p - inner] += w[r] * w[c] * ke[r * 24 + c];
      }
    }
  }

  // Column j of K holds every free DOF that shares an element with a DOF
  // mapped to j (linked DOFs map several mesh DOFs to one unknown).
  void BuildPattern() {
    const std::size_t nn = mesh_.nodes.size();
    std::vector<std::vector<int>> nbr(nn);
    for (const auto& el : mesh_.elements)
      for (int a : el)
        for (int b : el) nbr[a].push_back(b);
    for (auto& v : nbr) {
      std::sort(v.begin(), v.end());
      v.erase(std::unique(v.begin(), v.end()), v.end());
    }
    std::vector<std::vector<int>> rows(num_free_);
    for (std::size_t n = 0; n < nn; ++n)
      for (int c = 0; c < 3; ++c) {
        const int col = free_[3 * n + c];
        if (col < 0) continue;
        for (int m : nbr[n])
          for (int d = 0; d < 3; ++d) {
            const int row = free_[3 * static_cast<std::size_t>(m) + d];
            if (row >= 0) rows[col].push_back(row);
          }
      }
    std::vector<int> outer(num_free_ + 1, 0);
    std::vector<int> inner;
    for (int col = 0; col < num_free_; ++col) {
      auto& v = rows[col];
      std::sort(v.begin(), v.end());
      v.erase(std::unique(v.begin(), v.end()), v.end());
      inner.insert(inner.end(), v.begin(), v.end());
      outer[col + 1] = static_cast<int>(inner.size());
      std::vector<int>().swap(v);
    }
    K_.resize(num_free_, num_free_);
    K_.resizeNonZeros(static_cast<Eigen::Index>(inner.size()));
    std::copy(outer.begin(), outer.end(), K_.outerIndexPtr());
    std::copy(inner.begin(), inner.end(), K_.innerIndexPtr());
    std::fill(K_.valuePtr(), K_.valuePtr() + inner.size(), 0.0);
    diag_.resize(num_free_);
    for (int j = 0; j < num_free_; ++j) {
      const int* p = std::lower_bound(K_.innerIndexPtr() + outer[j], K_.innerIndexPtr() + outer[j + 1], j);
      diag_[j] = static_cast<int>(p - K_.innerIndexPtr());
    }
  }

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

StaticSolveSummary SolveStatic(const HexMesh& mesh, const Material& material,
                               const BoundaryConditions& bc, const StaticSolveOptions& options) {
  const auto t_start = Clock::now();
  StaticSolveSummary summary;
  if (mesh.elements.empty()) throw InputError("static solve: mesh has no elements");
  if (!(material.mu > 0) || !(material.kappa > 0)) {
    throw InputError("static solve: material needs mu > 0 and kappa > 0");
  }
  if (options.load_steps < 1) throw InputError("static solve: load_steps must be >= 1");
  const int nn = static_cast<int>(mesh.nodes.size());
  for (const auto& el : mesh.elements)
    for (int a : el)
      if (a < 0 || a >= nn) throw InputError("hex mesh: element node index " + std::to_string(a) + " out of range");
  const std::size_t ndof = 3 * static_cast<std::size_t>(nn);

  // DOF map and prescribed values.
  std::vector<int> free_index(ndof, 0);
  Eigen::VectorXd prescribed = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(ndof));
  for (const auto& d : bc.dirichlet) {
    if (d.node < 0 || d.node >= nn || d.component < 0 || d.component > 2 || !std::isfinite(d.value)) {
      throw InputError("dirichlet condition: node " + std::to_string(d.node) + " component " +
                       std::to_string(d.component) + " is invalid");
    }
    free_index[3 * d.node + d.component] = -1;
    prescribed[3 * d.node + d.component] = d.value;
  }
  std::vector<double> coefficient(ndof, 1.0);
  for (const auto& l : bc.links) {
    if (l.node < 0 || l.node >= nn || l.master < 0 || l.master >= nn || l.component < 0 ||
        l.component > 2 || l.node == l.master || !std::isfinite(l.factor)) {
      throw InputError("linked component: node " + std::to_string(l.node) + " master " +
                       std::to_string(l.master) + " is invalid");
    }
    const std::size_t k = 3 * static_cast<std::size_t>(l.node) + l.component;
    if (free_index[k] != 0) throw InputError("linked component: node " + std::to_string(l.node) + " is also prescribed or linked twice");
    free_index[k] = -2;  // resolved below
  }
  // Free unknowns numbered node by node in nested-dissection order
  // (nested_dissection.h): the factorisation keeps that order (below), so
  // its fill, its roundings and every FEM result depend on the mesh alone.
  int num_free = 0;
  for (int n : NestedDissectionOrder(mesh))
    for (int c = 0; c < 3; ++c)
      if (free_index[3 * static_cast<std::size_t>(n) + c] == 0) free_index[3 * static_cast<std::size_t>(n) + c] = num_free++;
  for (const auto& l : bc.links) {
    const std::size_t k = 3 * static_cast<std::size_t>(l.node) + l.component;
    const std::size_t m = 3 * static_cast<std::size_t>(l.master) + l.component;
    if (free_index[m] < 0) {
      throw InputError("linked component: master node " + std::to_string(l.master) + " must be free");
    }
    free_index[k] = free_index[m];
    coefficient[k] = l.factor;
  }
  if (num_free == 0) throw InputError("static solve: every degree of freedom is prescribed");

  Eigen::VectorXd f_total = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(ndof));
  for (const auto& nf : bc.nodal_forces) {
    if (nf.node < 0 || nf.node >= nn) throw InputError("nodal force: node " + std::to_string(nf.node) + " out of range");
    for (int i = 0; i < 3; ++i) f_total[3 * nf.node + i] += nf.force[i];
  }
  for (const auto& t : bc.tractions) AddFaceTraction(mesh, t, &f_total);

  std::vector<GaussPoint> gauss_points = PrecomputeGaussPoints(mesh);
  std::vector<double> problem_gauss_weights;
  problem_gauss_weights.reserve(gauss_points.size());
  for (const auto& gp : gauss_points) problem_gauss_weights.push_back(gp.weight);
  const bool incompatible = options.element == StaticSolveOptions::Element::kIncompatibleModes;
  Problem problem(mesh, material, std::move(gauss_points), free_index, coefficient, num_free, incompatible);
  summary.num_free_dofs = num_free;
  const Eigen::Index nf = num_free;
  auto restrict_free = [&](const Eigen::VectorXd& full) {
    Eigen::VectorXd r = Eigen::VectorXd::Zero(nf);
    for (std::size_t k = 0; k < ndof; ++k)
      if (free_index[k] >= 0) r[free_index[k]] += coefficient[k] * full[static_cast<Eigen::Index>(k)];
    return r;
  };
  const Eigen::VectorXd f_total_free = restrict_free(f_total);

  Cholesky solver;
#ifdef FABATLAS_FEM_HAVE_CHOLMOD
  solver.cholmod().print = 0;  // the shift below handles "not positive definite"
  // Orderings: the unknowns' own (nested dissection, above) or AMD, the
  // better of the two by CHOLMOD's analysis of both (fill and flops). Never
  // METIS or NESDIS, CHOLMOD's default candidates: METIS draws from the
  // process's one rand() generator, so its permutation changed with other
  // threads' draws (nested_dissection.h).
  solver.cholmod().nmethods = 2;
  solver.cholmod().method[0].ordering = CHOLMOD_NATURAL;
  solver.cholmod().method[1].ordering = CHOLMOD_AMD;
#endif
  bool analysed = false;
  const bool direct = options.linear_solver == StaticSolveOptions::LinearSolver::kCholesky;
  // Iterative alternatives (static_solve.h): K is stored in full, so both
  // triangles are used in the products.
  Eigen::ConjugateGradient<SpMat, Eigen::Lower | Eigen::Upper,
                           Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>>>
      cg_ic;
  Eigen::ConjugateGradient<SpMat, Eigen::Lower | Eigen::Upper, Eigen::DiagonalPreconditioner<double>> cg_jacobi;
  cg_ic.setTolerance(options.cg_relative_tolerance);
  cg_ic.setMaxIterations(options.cg_max_iterations);
  cg_jacobi.setTolerance(options.cg_relative_tolerance);
  cg_jacobi.setMaxIterations(options.cg_max_iterations);

  Eigen::VectorXd u = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(ndof));
  Eigen::VectorXd alpha = Eigen::VectorXd::Zero(problem.num_alpha());  // incompatible modes, mm
  Eigen::VectorXd f_int, f_cond, dalpha, d_full(static_cast<Eigen::Index>(ndof));
  auto potential = [&](const Eigen::VectorXd& x, const Eigen::VectorXd& a, double lambda) {
    return problem.StrainEnergy(x, a) - lambda * f_total.dot(x);
  };

  // Rounding noise of the energy sum: a few ulps of the energy density
  // scale (mu + kappa) times the reference volume.
  double volume = 0;
  for (const auto& gp : problem_gauss_weights) volume += gp;
  const double energy_noise = 1e-11 * (material.mu + material.kappa) * volume;

  double lambda = 0.0;
  double dlambda = 1.0 / options.load_steps;
  int cutbacks = 0;
  int easy_steps = 0;  // consecutive steps that converged quickly
  double last_shift_ratio = 0;  // last diagonal shift / mean diagonal
  while (lambda < 1.0 - 1e-14) {
    const double target = std::min(1.0, lambda + dlambda);
    const Eigen::VectorXd u_step_start = u;
    const Eigen::VectorXd alpha_step_start = alpha;
    for (std::size_t k = 0; k < ndof; ++k)
      if (free_index[k] < 0) u[static_cast<Eigen::Index>(k)] = target * prescribed[static_cast<Eigen::Index>(k)];
    const int iterations_before = summary.newton_iterations;
    bool step_ok = false;
    std::string failure;
    double scale = target * f_total_free.norm();
    // First attempt: full Newton steps (halved only while an element would
    // invert); if that does not converge, the increment is redone from its
    // start with the Armijo line search on the potential energy.
    for (int attempt = options.full_newton_first ? 0 : 1; attempt < 2 && !step_ok; ++attempt) {
    const bool line_search = attempt == 1;
    if (attempt == 1 && options.full_newton_first) {
      u = u_step_start;
      alpha = alpha_step_start;
      for (std::size_t k = 0; k < ndof; ++k)
        if (free_index[k] < 0) u[static_cast<Eigen::Index>(k)] = target * prescribed[static_cast<Eigen::Index>(k)];
      if (options.verbose) std::fprintf(stderr, "fem: full Newton steps failed (%s); line search\n", failure.c_str());
      failure.clear();
    }
    for (int it = 0; it < options.max_newton_iterations; ++it) {
      const auto ta = Clock::now();
      const double ra2 = problem.Assemble(u, alpha, &f_int, &f_cond, true);
      summary.assembly_seconds += Seconds(ta, Clock::now());
      // The gradient of Pi: r_u (free DOFs) and r_alpha; the Newton system
      // uses the condensed r (static condensation, Problem).
      const Eigen::VectorXd r_u = restrict_free(f_int) - target * f_total_free;
      const Eigen::VectorXd r = incompatible ? Eigen::VectorXd(restrict_free(f_cond) - target * f_total_free) : r_u;
      const double rnorm = std::sqrt(r_u.squaredNorm() + ra2);
      if (!std::isfinite(rnorm)) {
        failure = "non-finite residual (inverted element)";
        break;
      }
      if (it == 0) scale = std::max(scale, rnorm);
      summary.final_residual_norm = rnorm;
      if (options.verbose) {
        std::fprintf(stderr, "fem: lambda=%.4f it=%d |r|=%.3e scale=%.3e\n", target, it, rnorm, scale);
      }
      if (rnorm <= options.relative_tolerance * scale || scale == 0.0) {
        step_ok = true;
        break;
      }
      // Newton direction: K d = -r, K shifted until positive definite.
      const auto ts = Clock::now();
      SpMat& K = problem.K();
      if (!analysed && direct) {
        solver.analyzePattern(K);
        analysed = true;
#ifdef FABATLAS_FEM_HAVE_CHOLMOD
        if (options.verbose) {
          const cholmod_common& c = solver.cholmod();
          std::fprintf(stderr, "fem: ordering %s, factor entries %.4g, flops %.4g\n",
                       c.method[c.selected].ordering == CHOLMOD_AMD ? "AMD" : "nested dissection", c.lnz, c.fl);
        }
#endif
      }
      double mean_diag = 0;
      for (int j = 0; j < num_free; ++j) mean_diag += std::abs(K.valuePtr()[problem.diagonal_slots()[j]]);
      mean_diag /= num_free;
      double shift = 0;
      Eigen::VectorXd d;
      // One attempt at K d = -r with the current shift; false if K is not
      // (numerically) positive definite or the solve did not converge.
      auto try_solve = [&]() -> bool {
        ++summary.factorizations;
        if (direct) {
          solver.factorize(K);
          if (solver.info() != Eigen::Success) return false;
          d = solver.solve(-r);
          return true;
        }
        bool ok = false;
        if (options.linear_solver == StaticSolveOptions::LinearSolver::kConjugateGradientJacobi) {
          cg_jacobi.compute(K);
          d = cg_jacobi.solve(-r);
          summary.linear_iterations += cg_jacobi.iterations();
          ok = cg_jacobi.info() == Eigen::Success;
        } else {
          cg_ic.compute(K);
          if (cg_ic.preconditioner().info() != Eigen::Success) return false;
          d = cg_ic.solve(-r);
          summary.linear_iterations += cg_ic.iterations();
          ok = cg_ic.info() == Eigen::Success;
        }
        return ok && d.allFinite() && r.dot(d) < 0;
      };
      // Shifts: the first try uses a tenth of the last shift that worked
      // (none once that falls below 1e-6 x the mean diagonal, and none if
      // the last step needed none): the tangent changes little between
      // iterations, and every failed try is a factorisation. Then 1e-6 x the
      // mean diagonal or the last shift, times 10 each try.
      double first = 0.1 * last_shift_ratio >= 1e-6 ? 0.1 * last_shift_ratio * mean_diag : 0.0;
      if (first > 0) {
        for (int j = 0; j < num_free; ++j) K.valuePtr()[problem.diagonal_slots()[j]] += first;
        shift = first;
      }
      bool solved = try_solve();
      while (!solved && shift < 1e6 * mean_diag) {
        const double next = shift == 0 ? std::max(1e-6, 0.1 * last_shift_ratio) * mean_diag : shift * 10;
        for (int j = 0; j < num_free; ++j) K.valuePtr()[problem.diagonal_slots()[j]] += next - shift;
        shift = next;
        solved = try_solve();
      }
      last_shift_ratio = shift / mean_diag;
      if (!solved) {
        summary.linear_solve_seconds += Seconds(ts, Clock::now());
        failure = direct ? "tangent stiffness could not be factorised (a part not held by the fixed region?)"
                         : "conjugate gradients did not converge on the tangent stiffness (a part not held by "
                           "the fixed region?)";
        break;
      }
      summary.linear_solve_seconds += Seconds(ts, Clock::now());
      ++summary.newton_iterations;

      // The full step: d on the free DOFs (d_full on all DOFs) and the mode
      // increments it implies (static condensation).
      d_full.setZero();
      for (std::size_t k = 0; k < ndof; ++k) {
        const int fk = free_index[k];
        if (fk >= 0) d_full[static_cast<Eigen::Index>(k)] = coefficient[k] * d[fk];
      }
      const double slope_alpha = problem.AlphaIncrement(d_full, &dalpha);

      // Backtracking line search on the potential energy (Armijo).
      Eigen::VectorXd u_trial = u, alpha_trial = alpha;
      // Full Newton steps only need the trial's energy to be finite (no
      // inverted element), not the energy here.
      const double pi0 = line_search ? potential(u, alpha, target) : 0.0;
      const double slope = r_u.dot(d) + slope_alpha;  // dPi/dstep at step = 0 (< 0)
      double step = 1.0;
      bool accepted = false;
      for (int ls = 0; ls <= options.max_line_search_halvings; ++ls, step *= 0.5) {
        u_trial = u + step * d_full;
        alpha_trial = alpha + step * dalpha;
        const double pi = potential(u_trial, alpha_trial, target);
        if (!std::isfinite(pi)) continue;
        if (!line_search || pi <= pi0 + options.armijo_c * step * slope) {
          accepted = true;
          break;
        }
        // Near the solution the energy decrease (~ r.d/2) drops below the
        // rounding noise of the energy sum; then accept a step that reduces
        // the residual norm instead.
        if (std::isfinite(pi0) && std::abs(pi - pi0) <= energy_noise) {
          Eigen::VectorXd f_trial;
          const double ra2_trial = problem.Assemble(u_trial, alpha_trial, &f_trial, nullptr, false);
          const Eigen::VectorXd r_trial = restrict_free(f_trial) - target * f_total_free;
          if (std::sqrt(r_trial.squaredNorm() + ra2_trial) < rnorm) {
            accepted = true;
            break;
          }
        }
      }
      if (!accepted) {
        failure = "line search found no decrease of the energy";
        break;
      }
      if (options.verbose) {
        std::fprintf(stderr, "fem:   step %.3g shift=%.3g |d|=%.3e\n", step, shift, d.norm());
      }
      u = u_trial;
      alpha = alpha_trial;
      // Rounding floor: a full Newton step that moves no node by more than
      // step_tolerance relative to the displacement field is converged.
      if (step == 1.0 && d.lpNorm<Eigen::Infinity>() <= options.step_tolerance * u.lpNorm<Eigen::Infinity>()) {
        step_ok = true;
        break;
      }
    }
    }  // attempt
    if (step_ok) {
      lambda = target;
      ++summary.load_steps_taken;
      // After two quick steps in a row, a cut-back increment grows again
      // (doubling, up to the initial 1 / load_steps).
      easy_steps = summary.newton_iterations - iterations_before <= options.quick_step_iterations ? easy_steps + 1 : 0;
      if (easy_steps >= 2 && dlambda < 1.0 / options.load_steps) {
        dlambda = std::min(2 * dlambda, 1.0 / options.load_steps);
        easy_steps = 0;
      }
      continue;
    }
    easy_steps = 0;
    u = u_step_start;
    alpha = alpha_step_start;
    if (failure.empty()) {
      failure = "no convergence in " + std::to_string(options.max_newton_iterations) + " Newton iterations";
    }
    if (cutbacks >= options.max_cutbacks) {
      summary.message = failure + " at load factor " + std::to_string(target) + " after " +
                        std::to_string(cutbacks) + " cutbacks";
      break;
    }
    ++cutbacks;
    dlambda *= 0.5;
  }
  summary.converged = lambda >= 1.0 - 1e-14;
  if (!summary.converged && summary.message.empty()) summary.message = "did not reach the full load";

  summary.displacements.resize(static_cast<std::size_t>(nn));
  for (int n = 0; n < nn; ++n) {
    Vec3 d{u[3 * n], u[3 * n + 1], u[3 * n + 2]};
    summary.displacements[n] = d;
    summary.max_displacement = std::max(summary.max_displacement, std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
  }
  summary.max_principal_strain = problem.MaxPrincipalStrain(u, alpha);
  summary.total_seconds = Seconds(t_start, Clock::now());
  return summary;
}

}  // namespace fabatlas::fem
