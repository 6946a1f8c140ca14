// The analytic Jacobian of the solve's residuals (solve/assembly_cost.h).
#include "assembly_cost.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace fabatlas::assembly::internal {

FrameDerivatives ConnectorFrameDerivatives(const Eigen::Matrix4d& base, const Primitive& p, const double* s,
                                           int sym_axis) {
  using J = ceres::Jet<double, internal::kParamBlock>;
  J sj[internal::kParamBlock];
  for (int i = 0; i < internal::kParamBlock; ++i) sj[i] = J(s[i], i);
  const Mat4<J> local = internal::SymmetricConnectorFrame<J>(p, sj, sym_axis);
  FrameDerivatives out;
  Eigen::Matrix4d v;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) v(r, c) = local(r, c).a;
  out.m = base * v;
  for (int i = 0; i < internal::kParamBlock; ++i) {
    Eigen::Matrix4d d;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) d(r, c) = local(r, c).v[i];
    out.d[i] = base * d;
  }
  return out;
}

namespace {

// Derivative of RigidInverse(m) along dm: [dRᵀ, −(dRᵀ t + Rᵀ dt)].
Eigen::Matrix4d RigidInverseDerivative(const Eigen::Matrix4d& m, const Eigen::Matrix4d& dm) {
  Eigen::Matrix4d r = Eigen::Matrix4d::Zero();
  r.topLeftCorner<3, 3>() = dm.topLeftCorner<3, 3>().transpose();
  r.topRightCorner<3, 1>() = -(dm.topLeftCorner<3, 3>().transpose() * m.topRightCorner<3, 1>() +
                               m.topLeftCorner<3, 3>().transpose() * dm.topRightCorner<3, 1>());
  return r;
}

// The 12 closure rows (position, then rotation) from `row` of column i.
void Put12(double* jac, int row, int i, const Eigen::Matrix4d& d, double wt, double wrot) {
  for (int a = 0; a < 3; ++a) jac[(row + a) * internal::kParamBlock + i] = wt * d(a, 3);
  for (int a = 0; a < 3; ++a)
    for (int bb = 0; bb < 3; ++bb) jac[(row + 3 + 3 * a + bb) * internal::kParamBlock + i] = wrot * d(a, bb);
}

}  // namespace

AssemblyCost::AssemblyCost(AssemblyResidual f) : f_(std::move(f)) {
  const Kinematics& kin = *f_.kin;
  const int n = static_cast<int>(kin.prog->instances.size());
  for (size_t b = 0; b < 2 * kin.prog->connections.size(); ++b)
    mutable_parameter_block_sizes()->push_back(internal::kParamBlock);
  set_num_residuals(f_.NumResiduals());
  // subtree_[t][d]: part d lies in the subtree below tree edge t.
  std::vector<int> edge_of(n, -1), parent(n, -1);
  for (size_t t = 0; t < kin.tree.size(); ++t) {
    const auto [e, child] = kin.tree[t];
    const auto& c = kin.prog->connections[e];
    edge_of[child] = static_cast<int>(t);
    parent[child] = child == c.part_b ? c.part_a : c.part_b;
  }
  subtree_.assign(kin.tree.size(), std::vector<char>(n, 0));
  for (int d = 0; d < n; ++d)
    for (int u = d; u > 0 && edge_of[u] >= 0; u = parent[u]) subtree_[edge_of[u]][d] = 1;
  for (size_t b = 0; b < 2 * kin.prog->connections.size(); ++b) {
    const auto& c = kin.prog->connections[b / 2];
    const auto& specs = b % 2 == 0 ? c.params_a : c.params_b;
    std::array<bool, internal::kParamBlock> used{};
    for (size_t i = 0; i < specs.size(); ++i) used[i] = !kin.held[b][i];
    if (kin.sym_axis[b] >= 0) used[3] = true;
    used_.push_back(used);
  }
}

bool AssemblyCost::Evaluate(double const* const* params, double* residuals, double** jacobians) const {
  f_(params, residuals);
  if (!jacobians) return true;
  const int nr = num_residuals(), m = static_cast<int>(f_.kin->prog->connections.size());
  for (int b = 0; b < 2 * m; ++b)
    if (jacobians[b]) std::fill(jacobians[b], jacobians[b] + nr * internal::kParamBlock, 0.0);
  const Frames frames = FramesAt(params, jacobians);
  TreeJacobians(frames, jacobians);
  ClosingJacobians(frames, jacobians);
  SpacingJacobians(params, jacobians);
  return true;
}

AssemblyCost::Frames AssemblyCost::FramesAt(double const* const* params, double** jacobians) const {
  const Kinematics& kin = *f_.kin;
  const Program& prog = *kin.prog;
  const int m = static_cast<int>(prog.connections.size());
  Frames out;
  std::vector<FrameDerivatives>& fr = out.connector;
  fr.resize(2 * m);
  for (int e = 0; e < m; ++e) {
    const auto& c = prog.connections[e];
    for (int side = 0; side < 2; ++side) {
      const int b = 2 * e + side;
      const Primitive& p = side == 0 ? prog.PrimitiveA(c) : prog.PrimitiveB(c);
      const Eigen::Matrix4d& base = side == 0 ? kin.base_a[e] : kin.base_b[e];
      double x[internal::kParamBlock];
      kin.Effective<double>(b, params[b], x);
      if (jacobians[b]) {
        fr[b] = ConnectorFrameDerivatives(base, p, x, kin.sym_axis[b]);
      } else {
        fr[b].m = base * internal::SymmetricConnectorFrame<double>(p, x, kin.sym_axis[b]);
      }
    }
  }
  out.pose = kin.Poses<double>(params);
  for (int e : kin.closing) {
    const auto& c = prog.connections[e];
    out.fa.push_back(out.pose[c.part_a] * fr[2 * e].m * kin.align[e]);
    out.fb.push_back(out.pose[c.part_b] * fr[2 * e + 1].m);
  }
  return out;
}

int AssemblyCost::SpacingRow() const { return 12 * static_cast<int>(f_.kin->closing.size()); }
int AssemblyCost::TargetRow() const { return SpacingRow() + static_cast<int>(f_.spacing.size()); }
int AssemblyCost::EnergyRow() const { return TargetRow() + (f_.HasTargetRows() ? 12 : 0); }

// Tree parameters: world-frame factor G on the child's subtree.
void AssemblyCost::TreeJacobians(const Frames& frames, double** jacobians) const {
  const Kinematics& kin = *f_.kin;
  const Program& prog = *kin.prog;
  const std::vector<FrameDerivatives>& fr = frames.connector;
  const std::vector<Mat4<double>>& pose = frames.pose;
  for (size_t t = 0; t < kin.tree.size(); ++t) {
    const auto [e, child] = kin.tree[t];
    const auto& c = prog.connections[e];
    const bool child_is_b = child == c.part_b;
    const int parent = child_is_b ? c.part_a : c.part_b;
    // P_child = P_parent·F1·F2·F3.
    const Eigen::Matrix4d& m1 = child_is_b ? fr[2 * e].m : fr[2 * e + 1].m;
    const Eigen::Matrix4d& m3 = child_is_b ? fr[2 * e + 1].m : fr[2 * e].m;
    const Eigen::Matrix4d f2 = child_is_b ? kin.align[e] : RigidInverse<double>(kin.align[e]);
    const Eigen::Matrix4d inv3 = RigidInverse<double>(m3);
    const Eigen::Matrix4d inv_child = RigidInverse<double>(pose[child]);
    for (int side = 0; side < 2; ++side) {
      const int b = 2 * e + side;
      if (!jacobians[b]) continue;
      const bool first = (side == 0) == child_is_b;  // this side's frame is F1
      for (int i = 0; i < internal::kParamBlock; ++i) {
        if (!used_[b][i]) continue;
        const Eigen::Matrix4d dchild =
            first ? Eigen::Matrix4d(pose[parent] * fr[b].d[i] * f2 * inv3)
                  : Eigen::Matrix4d(pose[parent] * m1 * f2 * RigidInverseDerivative(m3, fr[b].d[i]));
        SubtreeRows(t, dchild * inv_child, i, frames, jacobians[b]);
      }
    }
  }
}

// Column i of the rows that depend on the poses of tree edge t's subtree,
// which parameter i moves by the world-frame factor g.
void AssemblyCost::SubtreeRows(std::size_t t, const Eigen::Matrix4d& g, int i, const Frames& frames,
                               double* jac) const {
  const Kinematics& kin = *f_.kin;
  const Program& prog = *kin.prog;
  const std::vector<char>& sub = subtree_[t];
  const double wc = f_.closure_weight, wr = f_.closure_weight * f_.rot_scale;
  for (size_t k = 0; k < kin.closing.size(); ++k) {
    const auto& cc = prog.connections[kin.closing[k]];
    const bool ina = sub[cc.part_a], inb = sub[cc.part_b];
    if (!ina && !inb) continue;
    Eigen::Matrix4d d = Eigen::Matrix4d::Zero();
    if (ina) d += g * frames.fa[k];
    if (inb) d -= g * frames.fb[k];
    Put12(jac, 12 * static_cast<int>(k), i, d, wc * f_.ClosingScale(k), wr * f_.ClosingScale(k));
  }
  if (f_.HasTargetRows() && sub[prog.target]) {
    const int objective_row = TargetRow();
    const Eigen::Matrix4d d = g * frames.pose[prog.target] * f_.target->offset;
    double w[9];
    f_.target->Rows<double>(d.topLeftCorner<3, 3>(), w);
    const double ts = f_.TargetScale();
    for (int a = 0; a < 3; ++a) jac[(objective_row + a) * internal::kParamBlock + i] = ts * d(a, 3);
    for (int a = 0; a < 9; ++a)
      jac[(objective_row + 3 + a) * internal::kParamBlock + i] = ts * f_.target_rot_scale * w[a];
  }
  if (f_.phase == Phase::kRelaxation) {
    const int energy_row = EnergyRow();
    for (size_t k = 0; k < f_.energy.size(); ++k) {
      const EnergyTerm& en = f_.energy[k];
      if (!sub[en.part]) continue;
      const Eigen::Vector4d com_world = frames.pose[en.part] * en.com.homogeneous();
      jac[(energy_row + static_cast<int>(k)) * internal::kParamBlock + i] = en.scale * g.row(2).dot(com_world);
    }
  }
}

// Closing-connection parameters: only their own closure residual.
void AssemblyCost::ClosingJacobians(const Frames& frames, double** jacobians) const {
  const Kinematics& kin = *f_.kin;
  const Program& prog = *kin.prog;
  const double wc = f_.closure_weight, wr = f_.closure_weight * f_.rot_scale;
  for (size_t k = 0; k < kin.closing.size(); ++k) {
    const int e = kin.closing[k];
    const auto& c = prog.connections[e];
    for (int side = 0; side < 2; ++side) {
      const int b = 2 * e + side;
      if (!jacobians[b]) continue;
      for (int i = 0; i < internal::kParamBlock; ++i) {
        if (!used_[b][i]) continue;
        const Eigen::Matrix4d& di = frames.connector[b].d[i];
        const Eigen::Matrix4d d = side == 0 ? Eigen::Matrix4d(frames.pose[c.part_a] * di * kin.align[e])
                                            : Eigen::Matrix4d(-(frames.pose[c.part_b] * di));
        Put12(jacobians[b], 12 * static_cast<int>(k), i, d, wc * f_.ClosingScale(k), wr * f_.ClosingScale(k));
      }
    }
  }
}

// Spacing f = |t1 − t2|·L − (w1 + w2)/2 (active when f < 0).
void AssemblyCost::SpacingJacobians(double const* const* params, double** jacobians) const {
  const double wc = f_.closure_weight;
  for (size_t k = 0; k < f_.spacing.size(); ++k) {
    const SpacingTerm& s = f_.spacing[k];
    const double diff = params[s.block1][0] - params[s.block2][0];
    if (std::abs(diff) * s.length - s.half_widths >= 0) continue;
    const double sign = diff < 0 ? -1.0 : 1.0;
    const int row = SpacingRow() + static_cast<int>(k);
    if (jacobians[s.block1]) jacobians[s.block1][row * internal::kParamBlock] += wc * sign * s.length;
    if (jacobians[s.block2]) jacobians[s.block2][row * internal::kParamBlock] -= wc * sign * s.length;
  }
}

}  // namespace fabatlas::assembly::internal
