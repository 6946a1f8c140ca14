// solve/kinematics.h (internal to fabatlas_assembly) — the assembly solve's
// reduced coordinates (FabHacks Sec. 4.3): part poses from connection
// parameters by forward kinematics along the program's spanning tree.
#pragma once

#include <array>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <ceres/jet.h>

#include "connector_frames.h"
#include "fabatlas/assembly/program.h"

namespace fabatlas::assembly::internal {

// One parameter block: the (up to) four parameters of one side of a
// connection (kParamBlock).
using Block = std::array<double, internal::kParamBlock>;

// The inverse of a rigid transform [R t; 0 1]: [Rᵀ −Rᵀt; 0 1].
template <typename T>
Mat4<T> RigidInverse(const Mat4<T>& m) {
  Mat4<T> r = Mat4<T>::Identity();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = m(j, i);
  for (int i = 0; i < 3; ++i) r(i, 3) = -(r(i, 0) * m(0, 3) + r(i, 1) * m(1, 3) + r(i, 2) * m(2, 3));
  return r;
}

// Reduced coordinates (FabHacks, 4.3: "a reduced representation of a kinematic
// rigid body chain"): the environment pose is fixed and every other part pose
// follows from the connection parameters by forward kinematics along a
// spanning tree, P_b = P_a·M_a(s_a)·A·M_b(s_b)⁻¹. Tree connections therefore
// hold exactly; each non-tree connection closes a cycle and contributes the
// 12 residuals of P_a·M_a·A − P_b·M_b (position mm, rotation × scale).
struct Kinematics {
  const Program* prog;
  std::vector<std::pair<int, int>> tree;  // (connection, child) in BFS order
  std::vector<int> closing;               // non-tree connections
  std::vector<Eigen::Matrix4d> base_a, base_b, align;
  Eigen::Matrix4d env;
  // Per parameter block (2e + side): symmetry axis (-1 none) and the values
  // of held (base-form) parameters, which replace the block's own.
  std::vector<int> sym_axis;
  std::vector<std::array<bool, internal::kParamBlock>> held;
  std::vector<std::array<double, internal::kParamBlock>> held_value;

  template <typename T>
  void Effective(int b, const T* s, T* out) const {
    for (int i = 0; i < internal::kParamBlock; ++i) out[i] = held[b][i] ? T(held_value[b][i]) : s[i];
  }

  template <typename T>
  void Frames(int e, const T* sa, const T* sb, Mat4<T>& ma, Mat4<T>& mb) const {
    const auto& c = prog->connections[e];
    T xa[internal::kParamBlock], xb[internal::kParamBlock];
    Effective<T>(2 * e, sa, xa);
    Effective<T>(2 * e + 1, sb, xb);
    ma = base_a[e].template cast<T>() * internal::SymmetricConnectorFrame<T>(prog->PrimitiveA(c), xa, sym_axis[2 * e]);
    mb = base_b[e].template cast<T>() *
         internal::SymmetricConnectorFrame<T>(prog->PrimitiveB(c), xb, sym_axis[2 * e + 1]);
  }

  // params[2e] = s_a of connection e, params[2e+1] = s_b.
  template <typename T>
  std::vector<Mat4<T>> Poses(T const* const* params) const {
    std::vector<Mat4<T>> p(prog->instances.size(), Mat4<T>::Identity());
    p[0] = env.template cast<T>();
    for (const auto& [e, child] : tree) {
      const auto& c = prog->connections[e];
      Mat4<T> ma, mb;
      Frames<T>(e, params[2 * e], params[2 * e + 1], ma, mb);
      if (child == c.part_b)
        p[child] = p[c.part_a] * ma * align[e].template cast<T>() * RigidInverse<T>(mb);
      else
        p[child] = p[c.part_b] * mb * RigidInverse<T>(Mat4<T>(align[e].template cast<T>())) * RigidInverse<T>(ma);
    }
    return p;
  }
};

// The value of a double or of a Jet (its real part).
inline double Value(double x) { return x; }
template <int N>
double Value(const ceres::Jet<double, N>& x) {
  return x.a;
}

}  // namespace fabatlas::assembly::internal
