// The discrete problem of a static solve (static_solve/problem.h).
#include "problem.h"

#include <algorithm>
#include <functional>
#include <utility>

#include <Eigen/Dense>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

namespace fabatlas::fem::internal {

Problem::Problem(const HexMesh& mesh, const Material& mat, std::vector<GaussPoint> gps, std::vector<int> free_index,
                 std::vector<double> coefficient, int num_free, bool incompatible)
    : mesh_(mesh),
      mat_(mat),
      gps_(std::move(gps)),
      free_(std::move(free_index)),
      coef_(std::move(coefficient)),
      num_free_(num_free),
      incompatible_(incompatible) {
  BuildPattern();
  if (incompatible_) {
    const std::size_t ne = mesh_.elements.size();
    cond_M_.assign(ne * 216, 0.0);
    cond_m_.assign(ne * 9, 0.0);
    f_alpha_.assign(ne * 9, 0.0);
  }
}

double Problem::StrainEnergy(const Eigen::VectorXd& u, const Eigen::VectorXd& alpha) const {
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

double Problem::Assemble(const Eigen::VectorXd& u, const Eigen::VectorXd& alpha, Eigen::VectorXd* f_int,
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
    tbb::parallel_for(tbb::blocked_range<std::size_t>(b0, b1, 64), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t e = r.begin(); e < r.end(); ++e) {
        ElementKernel(e, u, alpha, &fe_[(e - b0) * 24], &fc_[(e - b0) * 24], want_K ? &ke_[(e - b0) * 576] : nullptr);
      }
    });
    for (std::size_t e = b0; e < b1; ++e) {
      Scatter(e, &fe_[(e - b0) * 24], want_K ? &fc_[(e - b0) * 24] : nullptr, want_K ? &ke_[(e - b0) * 576] : nullptr,
              f_int, f_cond);
    }
  }
  double fa2 = 0;
  for (double v : f_alpha_) fa2 += v * v;
  return fa2;
}

double Problem::AlphaIncrement(const Eigen::VectorXd& du, Eigen::VectorXd* dalpha) const {
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

double Problem::MaxPrincipalStrain(const Eigen::VectorXd& u, const Eigen::VectorXd& alpha) const {
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

// Element forces fe (24, dW/du) and, if ke, the tangent (24 x 24) and the
// condensed forces fc (24). The incompatible-mode element treats its three
// modes as three extra "nodes" with gradients G_k (33 unknowns), then
// condenses them out.
void Problem::ElementKernel(std::size_t e, const Eigen::VectorXd& u, const Eigen::VectorXd& alpha, double* fe,
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
  Condense(e, f, k33, fc, ke);
}

// Static condensation of the element's modes (Simo & Armero 1992, Sec. 5):
// the condensed tangent into ke, the condensed forces into fc, and
// K_aa^-1 K_au, K_aa^-1 r_a for AlphaIncrement. K_aa is shifted until
// positive definite (like the global tangent), which keeps the step a
// descent direction.
void Problem::Condense(std::size_t e, const double* f, const double* k33, double* fc, double* ke) {
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

void Problem::Scatter(std::size_t e, const double* fe, const double* fc, const double* ke, Eigen::VectorXd* f_int,
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
void Problem::BuildPattern() {
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

}  // namespace fabatlas::fem::internal
