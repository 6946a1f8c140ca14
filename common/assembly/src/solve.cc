#include "fabatlas/assembly/solve.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <deque>
#include <memory>
#include <queue>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "connector_frames.h"
#include "fabatlas/assembly/precheck.h"
#include "solve_internal.h"

namespace fabatlas::assembly {
namespace {

using internal::Mat4;

template <typename T>
Mat4<T> RigidInverse(const Mat4<T>& m) {
  Mat4<T> r = Mat4<T>::Identity();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = m(j, i);
  for (int i = 0; i < 3; ++i) r(i, 3) = -(r(i, 0) * m(0, 3) + r(i, 1) * m(1, 3) + r(i, 2) * m(2, 3));
  return r;
}

enum class Phase { kFeasibility, kObjective, kRelaxation };

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

double Value(double x) { return x; }
template <int N>
double Value(const ceres::Jet<double, N>& x) { return x.a; }

// The end_with target (PARTS.md §2.1, §2.4): the world frame of the end
// primitive, P·B, against the target frame, position in mm and rotation up
// to the symmetry of the end primitive's class. An Euler component the class
// ignores makes the rotation residual blind to it: a (rotation about the
// local x axis) compares only R·e_x; c (about the world z axis) only the
// third row of R; b only Rz(c_t)ᵀ·R·Rx(a_t)ᵀ·e_y. A period of 180 on c
// (clip, surface) also accepts Rz(180)·R_t. Rotation rows are linear in R, so
// their derivative is the same map applied to dR.
struct TargetForm {
  Eigen::Matrix4d offset = Eigen::Matrix4d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity(), twin = Eigen::Matrix3d::Identity();
  bool has_twin = false;
  int ignore = -1;  // Euler component ignored: 0 a, 1 b, 2 c
  Eigen::Matrix3d left = Eigen::Matrix3d::Identity(), right = Eigen::Matrix3d::Identity();

  static TargetForm Of(const Program& prog) {
    TargetForm f;
    f.offset = prog.TargetOffset();
    f.t = prog.target_frame.position;
    f.r = EulerToRotation(prog.target_frame.euler_deg);
    switch (prog.TargetPrimitive().type) {
      case PrimitiveType::kRing: f.ignore = 0; break;
      case PrimitiveType::kTube: f.ignore = 1; break;
      case PrimitiveType::kRod:
      case PrimitiveType::kHemisphere: f.ignore = 2; break;
      case PrimitiveType::kClip:
      case PrimitiveType::kSurface:
        f.has_twin = true;
        f.twin = EulerToRotation(Eigen::Vector3d(0, 0, 180)) * f.r;
        break;
      default: break;
    }
    // Euler angles of the target (PARTS.md: b = −asin R31, a = atan2(R32, R33), c = atan2(R21, R11)).
    const double a = std::atan2(f.r(2, 1), f.r(2, 2)) * 180 / M_PI, c = std::atan2(f.r(1, 0), f.r(0, 0)) * 180 / M_PI;
    f.left = EulerToRotation(Eigen::Vector3d(0, 0, c)).transpose();
    f.right = EulerToRotation(Eigen::Vector3d(a, 0, 0)).transpose();
    return f;
  }

  // W(R): the rotation quantities compared (9 values; unused ones 0).
  template <typename T>
  void Rows(const Eigen::Matrix<T, 3, 3>& R, T* out) const {
    for (int i = 0; i < 9; ++i) out[i] = T(0);
    if (ignore == 0) {
      for (int i = 0; i < 3; ++i) out[i] = R(i, 0);
    } else if (ignore == 2) {
      for (int i = 0; i < 3; ++i) out[i] = R(2, i);
    } else if (ignore == 1) {
      const Eigen::Matrix<T, 3, 3> m = left.cast<T>() * R * right.cast<T>();
      for (int i = 0; i < 3; ++i) out[i] = m(i, 1);
    } else {
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) out[3 * i + j] = R(i, j);
    }
  }

  // W(R) − W(target), with the nearer of the target and its twin.
  template <typename T>
  void RotationResidual(const Eigen::Matrix<T, 3, 3>& R, T* out) const {
    T w[9];
    Rows<T>(R, w);
    double t1[9], t2[9];
    Rows<double>(r, t1);
    Rows<double>(twin, t2);
    double d1 = 0, d2 = 0;
    for (int i = 0; i < 9; ++i) d1 += std::pow(Value(w[i]) - t1[i], 2), d2 += std::pow(Value(w[i]) - t2[i], 2);
    const double* tt = has_twin && d2 < d1 ? t2 : t1;
    for (int i = 0; i < 9; ++i) out[i] = w[i] - T(tt[i]);
  }

  // Position error (mm) and rotation error (degrees) up to the symmetry.
  void Errors(const Eigen::Matrix4d& part_pose, double& mm, double& deg) const {
    const Eigen::Matrix4d q = part_pose * offset;
    mm = (q.topRightCorner<3, 1>() - t).norm();
    const Eigen::Matrix3d R = q.topLeftCorner<3, 3>();
    auto angle = [&](const Eigen::Matrix3d& target) {
      auto between = [](const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
        return std::atan2(u.cross(v).norm(), u.dot(v)) * 180 / M_PI;
      };
      if (ignore == 0) return between(R.col(0), target.col(0));
      if (ignore == 2) return between(R.row(2).transpose(), target.row(2).transpose());
      if (ignore == 1) return between((left * R * right).col(1), (left * target * right).col(1));
      return RotationAngleDeg(R, target);
    };
    deg = angle(r);
    if (has_twin) deg = std::min(deg, angle(twin));
  }
};

struct SpacingTerm {
  int block1, block2;  // parameter block indices (2e + side)
  double length, half_widths;
};

struct EnergyTerm {
  int part;
  Eigen::Vector3d com;
  double scale;         // sqrt(m g / (1000 D))
  double datum;         // −D (mm), see AssemblyResidual
};

// All residuals of one phase as one cost over all parameter blocks.
struct AssemblyResidual {
  const Kinematics* kin;
  Phase phase;
  double closure_weight, rot_scale, target_rot_scale;
  // Relaxation only: residual scale of the target term (0: none), see
  // SolveOptions::relaxation_target_weight.
  double relax_target_scale = 0;
  bool HasTargetRows() const { return phase == Phase::kObjective || (phase == Phase::kRelaxation && relax_target_scale > 0); }
  double TargetScale() const { return phase == Phase::kObjective ? 1.0 : relax_target_scale; }
  std::vector<SpacingTerm> spacing;
  std::vector<EnergyTerm> energy;
  const TargetForm* target = nullptr;
  // Per closing connection (kin->closing order): multiplies its closure
  // residuals; empty = all 1. A chain solve (Solver::SetChainStart) switches
  // off the cycles it does not close.
  std::vector<double> closing_scale;
  double ClosingScale(size_t k) const { return closing_scale.empty() ? 1.0 : closing_scale[k]; }

  int NumResiduals() const {
    return 12 * static_cast<int>(kin->closing.size()) + static_cast<int>(spacing.size()) +
           (HasTargetRows() ? 12 : 0) + (phase == Phase::kRelaxation ? static_cast<int>(energy.size()) : 0);
  }

  template <typename T>
  bool operator()(T const* const* params, T* r) const {
    const std::vector<Mat4<T>> p = kin->Poses<T>(params);
    int k = 0;
    for (size_t ci = 0; ci < kin->closing.size(); ++ci) {
      const int e = kin->closing[ci];
      const auto& c = kin->prog->connections[e];
      Mat4<T> ma, mb;
      kin->Frames<T>(e, params[2 * e], params[2 * e + 1], ma, mb);
      const Mat4<T> fa = p[c.part_a] * ma * kin->align[e].template cast<T>();
      const Mat4<T> fb = p[c.part_b] * mb;
      const double w = closure_weight * ClosingScale(ci);
      for (int i = 0; i < 3; ++i) r[k++] = T(w) * (fa(i, 3) - fb(i, 3));
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r[k++] = T(w * rot_scale) * (fa(i, j) - fb(i, j));
    }
    // Multi-connection spacing (FabHacks, 4.3.1): f = |t1 − t2|·L − (w1 + w2)/2, f² if f < 0.
    for (const auto& s : spacing) {
      T d = params[s.block1][0] - params[s.block2][0];
      if (d < T(0)) d = -d;
      const T f = d * T(s.length) - T(s.half_widths);
      r[k++] = f < T(0) ? T(closure_weight) * f : T(0);
    }
    if (HasTargetRows()) {
      const Mat4<T> q = p[kin->prog->target] * target->offset.template cast<T>();
      const double ts = TargetScale();
      for (int i = 0; i < 3; ++i) r[k++] = T(ts) * (q(i, 3) - T(target->t[i]));
      T w[9];
      target->RotationResidual<T>(q.template topLeftCorner<3, 3>(), w);
      for (int i = 0; i < 9; ++i) r[k++] = T(ts * target_rot_scale) * w[i];
    }
    if (phase == Phase::kRelaxation) {
      // Potential m·g·z (J, z in mm/1000) as ½r² = m g (z + D)² / (2000 D):
      // gradient m g (z + D)/(1000 D) = m g/1000 up to a relative |z|/D < 1e-2.
      for (const auto& en : energy) {
        const Mat4<T>& q = p[en.part];
        T z = q(2, 3);
        for (int i = 0; i < 3; ++i) z += q(2, i) * T(en.com[i]);
        r[k++] = T(en.scale) * (z - T(en.datum));
      }
    }
    return true;
  }
};

// Connector frame M = base·M_local(s) and its partial derivatives dM/ds_i of
// one parameter block (i = 0..3), from one pass of 4-wide forward-mode Jets
// through the local frame only (the constant base frame stays in double).
struct FrameDerivatives {
  Eigen::Matrix4d m;
  std::array<Eigen::Matrix4d, internal::kParamBlock> d;
};

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

// Derivative of RigidInverse(m) along dm: [dRᵀ, −(dRᵀ t + Rᵀ dt)].
Eigen::Matrix4d RigidInverseDerivative(const Eigen::Matrix4d& m, const Eigen::Matrix4d& dm) {
  Eigen::Matrix4d r = Eigen::Matrix4d::Zero();
  r.topLeftCorner<3, 3>() = dm.topLeftCorner<3, 3>().transpose();
  r.topRightCorner<3, 1>() = -(dm.topLeftCorner<3, 3>().transpose() * m.topRightCorner<3, 1>() +
                               m.topLeftCorner<3, 3>().transpose() * dm.topRightCorner<3, 1>());
  return r;
}

// AssemblyResidual with analytic Jacobians (same residuals). Forward
// kinematics makes each part pose a product of per-connection frames, so a
// parameter s of tree connection e (child c) changes every pose of c's
// subtree by the same world-frame factor: dP_d/ds = G·P_d with
// G = (dP_c/ds)·P_c⁻¹. A parameter of a closing connection only enters its
// own closure residual. Costs a few 4×4 double products per parameter instead
// of carrying derivative vectors through the whole chain (autodiff).
class AssemblyCost : public ceres::CostFunction {
 public:
  explicit AssemblyCost(AssemblyResidual f) : f_(std::move(f)) {
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
      const Primitive& p = b % 2 == 0 ? kin.prog->PrimitiveA(c) : kin.prog->PrimitiveB(c);
      const auto& specs = b % 2 == 0 ? c.params_a : c.params_b;
      std::array<bool, internal::kParamBlock> used{};
      for (size_t i = 0; i < specs.size(); ++i) used[i] = !kin.held[b][i];
      if (kin.sym_axis[b] >= 0) used[3] = true;
      used_.push_back(used);
    }
  }

  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override {
    f_(params, residuals);
    if (!jacobians) return true;
    const Kinematics& kin = *f_.kin;
    const Program& prog = *kin.prog;
    const int nr = num_residuals(), m = static_cast<int>(prog.connections.size());
    for (int b = 0; b < 2 * m; ++b)
      if (jacobians[b]) std::fill(jacobians[b], jacobians[b] + nr * internal::kParamBlock, 0.0);
    // Frames (values; derivatives only where a Jacobian is asked for).
    std::vector<FrameDerivatives> fr(2 * m);
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
    const std::vector<Mat4<double>> pose = kin.Poses<double>(params);
    // Closure frames fa = P_a·M_a·A, fb = P_b·M_b of every closing connection.
    std::vector<Eigen::Matrix4d> fa, fb;
    for (int e : kin.closing) {
      const auto& c = prog.connections[e];
      fa.push_back(pose[c.part_a] * fr[2 * e].m * kin.align[e]);
      fb.push_back(pose[c.part_b] * fr[2 * e + 1].m);
    }
    const double wc = f_.closure_weight, wr = f_.closure_weight * f_.rot_scale;
    const int spacing_row = 12 * static_cast<int>(kin.closing.size());
    const int objective_row = spacing_row + static_cast<int>(f_.spacing.size());
    const int energy_row = objective_row + (f_.HasTargetRows() ? 12 : 0);
    auto put12 = [&](double* jac, int row, int i, const Eigen::Matrix4d& d, double wt, double wrot) {
      for (int a = 0; a < 3; ++a) jac[(row + a) * internal::kParamBlock + i] = wt * d(a, 3);
      for (int a = 0; a < 3; ++a)
        for (int bb = 0; bb < 3; ++bb) jac[(row + 3 + 3 * a + bb) * internal::kParamBlock + i] = wrot * d(a, bb);
    };
    // Tree parameters: world-frame factor G on the child's subtree.
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
      const std::vector<char>& sub = subtree_[t];
      for (int side = 0; side < 2; ++side) {
        const int b = 2 * e + side;
        if (!jacobians[b]) continue;
        const bool first = (side == 0) == child_is_b;  // this side's frame is F1
        for (int i = 0; i < internal::kParamBlock; ++i) {
          if (!used_[b][i]) continue;
          const Eigen::Matrix4d dchild = first ? Eigen::Matrix4d(pose[parent] * fr[b].d[i] * f2 * inv3)
                                               : Eigen::Matrix4d(pose[parent] * m1 * f2 *
                                                                 RigidInverseDerivative(m3, fr[b].d[i]));
          const Eigen::Matrix4d g = dchild * inv_child;
          double* jac = jacobians[b];
          for (size_t k = 0; k < kin.closing.size(); ++k) {
            const auto& cc = prog.connections[kin.closing[k]];
            const bool ina = sub[cc.part_a], inb = sub[cc.part_b];
            if (!ina && !inb) continue;
            Eigen::Matrix4d d = Eigen::Matrix4d::Zero();
            if (ina) d += g * fa[k];
            if (inb) d -= g * fb[k];
            put12(jac, 12 * static_cast<int>(k), i, d, wc * f_.ClosingScale(k), wr * f_.ClosingScale(k));
          }
          if (f_.HasTargetRows() && sub[prog.target]) {
            const Eigen::Matrix4d d = g * pose[prog.target] * f_.target->offset;
            double w[9];
            f_.target->Rows<double>(d.topLeftCorner<3, 3>(), w);
            const double ts = f_.TargetScale();
            for (int a = 0; a < 3; ++a) jac[(objective_row + a) * internal::kParamBlock + i] = ts * d(a, 3);
            for (int a = 0; a < 9; ++a)
              jac[(objective_row + 3 + a) * internal::kParamBlock + i] = ts * f_.target_rot_scale * w[a];
          }
          if (f_.phase == Phase::kRelaxation)
            for (size_t k = 0; k < f_.energy.size(); ++k) {
              const EnergyTerm& en = f_.energy[k];
              if (!sub[en.part]) continue;
              const Eigen::Vector4d com_world = pose[en.part] * en.com.homogeneous();
              jac[(energy_row + static_cast<int>(k)) * internal::kParamBlock + i] = en.scale * g.row(2).dot(com_world);
            }
        }
      }
    }
    // Closing-connection parameters: only their own closure residual.
    for (size_t k = 0; k < kin.closing.size(); ++k) {
      const int e = kin.closing[k];
      const auto& c = prog.connections[e];
      for (int side = 0; side < 2; ++side) {
        const int b = 2 * e + side;
        if (!jacobians[b]) continue;
        for (int i = 0; i < internal::kParamBlock; ++i) {
          if (!used_[b][i]) continue;
          const Eigen::Matrix4d d = side == 0 ? Eigen::Matrix4d(pose[c.part_a] * fr[b].d[i] * kin.align[e])
                                              : Eigen::Matrix4d(-(pose[c.part_b] * fr[b].d[i]));
          put12(jacobians[b], 12 * static_cast<int>(k), i, d, wc * f_.ClosingScale(k), wr * f_.ClosingScale(k));
        }
      }
    }
    // Spacing f = |t1 − t2|·L − (w1 + w2)/2 (active when f < 0).
    for (size_t k = 0; k < f_.spacing.size(); ++k) {
      const SpacingTerm& s = f_.spacing[k];
      const double diff = params[s.block1][0] - params[s.block2][0];
      if (std::abs(diff) * s.length - s.half_widths >= 0) continue;
      const double sign = diff < 0 ? -1.0 : 1.0;
      const int row = spacing_row + static_cast<int>(k);
      if (jacobians[s.block1]) jacobians[s.block1][row * internal::kParamBlock] += wc * sign * s.length;
      if (jacobians[s.block2]) jacobians[s.block2][row * internal::kParamBlock] -= wc * sign * s.length;
    }
    return true;
  }

 private:
  AssemblyResidual f_;
  std::vector<std::vector<char>> subtree_;  // per tree edge, per part
  std::vector<std::array<bool, internal::kParamBlock>> used_;
};

// Gauge fix of the relaxation: ½k‖s − s₀‖² for one parameter block, s₀ the
// parameters the relaxation starts from (step 1). A hanging part whose centre
// of mass is below its support may turn about the vertical at no energy cost;
// without this term that turn is left to round-off and the relaxed pose is
// not reproducible. k (J per unit², degrees for angles; default 1e-9) is far
// below the gravity stiffness of a swing, m g L/1000·(π/180)² (5e-7 J/deg²
// for 5 g on a 30 mm lever), so it picks one of equivalent equilibria and
// moves a true one by a relative ≲ k / that stiffness.
class AnchorCost : public ceres::SizedCostFunction<internal::kParamBlock, internal::kParamBlock> {
 public:
  // `unit`: mm per unit of each parameter (a slide parameter t moves the
  // contact by the primitive's length per unit), 1 for angles (degrees).
  AnchorCost(const std::array<double, internal::kParamBlock>& anchor, double stiffness,
             const std::array<double, internal::kParamBlock>& unit)
      : anchor_(anchor) {
    for (int i = 0; i < internal::kParamBlock; ++i) w_[i] = std::sqrt(stiffness) * unit[i];
  }
  bool Evaluate(double const* const* x, double* r, double** jac) const override {
    for (int i = 0; i < internal::kParamBlock; ++i) r[i] = w_[i] * (x[0][i] - anchor_[i]);
    if (jac && jac[0])
      for (int i = 0; i < internal::kParamBlock * internal::kParamBlock; ++i)
        jac[0][i] = i % (internal::kParamBlock + 1) == 0 ? w_[i / internal::kParamBlock] : 0.0;
    return true;
  }

 private:
  std::array<double, internal::kParamBlock> anchor_;
  std::array<double, internal::kParamBlock> w_;
};

// Stall prevention (FabHacks, 4.3.2): linear regression of log10(cost) over a
// sliding window; abort when it decreases slower than `slope` per iteration.
class StallCallback : public ceres::IterationCallback {
 public:
  StallCallback(int window, double slope, double floor) : window_(window), slope_(slope), floor_(floor) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    const double c = 2 * s.cost;
    if (c < floor_) return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
    logs_.push_back(std::log10(std::max(c, 1e-300)));
    if (static_cast<int>(logs_.size()) > window_) logs_.pop_front();
    if (static_cast<int>(logs_.size()) < window_) return ceres::SOLVER_CONTINUE;
    double mx = 0, my = 0;
    const int n = static_cast<int>(logs_.size());
    for (int i = 0; i < n; ++i) mx += i, my += logs_[i];
    mx /= n;
    my /= n;
    double sxy = 0, sxx = 0;
    for (int i = 0; i < n; ++i) sxy += (i - mx) * (logs_[i] - my), sxx += (i - mx) * (i - mx);
    return sxy / sxx > -slope_ ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
  }

 private:
  int window_;
  double slope_, floor_;
  std::deque<double> logs_;
};

using Block = std::array<double, internal::kParamBlock>;

// Step 2 stopping rule on the motion itself: LM creeps along a soft mode of
// a hanging chain with steps of ~1e-6 (its Gauss-Newton model has no
// curvature along a swing), so after `window` iterations in which no
// parameter moved by more than `motion` (mm or degrees) the relaxation is
// converged for every purpose here (Ceres reports USER_SUCCESS). The
// reproducibility test (relaxation_test) bounds what this leaves.
class RelaxationWindow : public ceres::IterationCallback {
 public:
  RelaxationWindow(const std::vector<Block>& blocks, int window, double motion)
      : blocks_(blocks), window_(window), motion_(motion), last_(blocks) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& it) override {
    if (window_ <= 0 || it.iteration == 0 || it.iteration % window_ != 0) return ceres::SOLVER_CONTINUE;
    double moved = 0;
    for (size_t b = 0; b < blocks_.size(); ++b)
      for (int i = 0; i < internal::kParamBlock; ++i) moved = std::max(moved, std::abs(blocks_[b][i] - last_[b][i]));
    last_ = blocks_;
    if (std::getenv("FABATLAS_ASSEMBLY_DEBUG"))
      std::fprintf(stderr, "  relaxation it %d: cost %.12e, largest motion over the window %.3e\n", it.iteration,
                   it.cost, moved);
    return moved < motion_ ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }

 private:
  const std::vector<Block>& blocks_;
  int window_;
  double motion_;
  std::vector<Block> last_;
};

// One chain of the chain-by-chain initial guess (Solver::SetChainStart):
// which connections' parameters move, and which cycles are closed.
struct Chain {
  std::vector<char> free;              // per connection
  std::vector<double> closing_scale;   // per closing connection: 1 closed by this chain, 0 ignored
};

double Halton(int index, int base) {
  double f = 1, r = 0;
  while (index > 0) {
    f /= base;
    r += f * (index % base);
    index /= base;
  }
  return r;
}

// One slide along a rod, tube or edge that static friction acts on
// (SolveOptions::slide_friction): parameter `index` of block `block`.
struct SlideState {
  int block, index;
  bool stuck = false;            // held at its value by friction
  double axial = 0, normal = 0;  // load along / across the axis (J/mm = kN), last evaluated
  double angle_deg = 0;          // atan(axial / normal), degrees, last evaluated
  double slip_angle_deg = 0;     // the angle at which it was let go
};

class Solver {
 public:
  Solver(const Program& prog, const SolveOptions& opt) : prog_(prog), opt_(opt) {
    const int n = static_cast<int>(prog.instances.size());
    const int m = static_cast<int>(prog.connections.size());
    blocks_.assign(2 * m, Block{0, 0, 0, 0});
    kin_.prog = &prog;
    kin_.env = ToIsometry(prog.environment_frame).matrix();
    target_ = TargetForm::Of(prog);
    for (const auto& c : prog.connections) {
      kin_.base_a.push_back(ToIsometry(prog.PrimitiveA(c).frame).matrix());
      kin_.base_b.push_back(ToIsometry(prog.PrimitiveB(c).frame).matrix());
      Eigen::Matrix4d a = Eigen::Matrix4d::Identity();
      a.topLeftCorner<3, 3>() = c.align;
      kin_.align.push_back(a);
      for (int side = 0; side < 2; ++side) {
        const auto& specs = side == 0 ? c.params_a : c.params_b;
        std::array<bool, internal::kParamBlock> held{};
        std::array<double, internal::kParamBlock> value{};
        for (size_t i = 0; i < specs.size(); ++i) held[i] = specs[i].held, value[i] = specs[i].init;
        kin_.held.push_back(held);
        kin_.held_value.push_back(value);
        kin_.sym_axis.push_back(side == 0 ? c.symmetry_axis_a : -1);
      }
    }
    // The spanning tree is the program's attach steps (each places its new
    // part b from the placed part a); connect steps close cycles.
    for (int e = 0; e < m; ++e) {
      if (prog.connections[e].closing) kin_.closing.push_back(e);
      else kin_.tree.push_back({e, prog.connections[e].part_b});
    }
    // Spacing terms for connections sharing one rod/tube/edge.
    for (int b1 = 0; b1 < 2 * m; ++b1)
      for (int b2 = b1 + 1; b2 < 2 * m; ++b2) {
        const auto& c1 = prog.connections[b1 / 2];
        const auto& c2 = prog.connections[b2 / 2];
        if (b1 / 2 == b2 / 2) continue;
        const int i1 = b1 % 2 == 0 ? c1.part_a : c1.part_b, i2 = b2 % 2 == 0 ? c2.part_a : c2.part_b;
        const std::string& n1 = b1 % 2 == 0 ? c1.primitive_a : c1.primitive_b;
        const std::string& n2 = b2 % 2 == 0 ? c2.primitive_a : c2.primitive_b;
        if (i1 != i2 || n1 != n2) continue;
        const Primitive& host = *prog.PartOf(i1).Find(n1);
        if (host.type != PrimitiveType::kRod && host.type != PrimitiveType::kTube && host.type != PrimitiveType::kEdge)
          continue;
        const Primitive& g1 = b1 % 2 == 0 ? prog.PrimitiveB(c1) : prog.PrimitiveA(c1);
        const Primitive& g2 = b2 % 2 == 0 ? prog.PrimitiveB(c2) : prog.PrimitiveA(c2);
        spacing_.push_back(
            {b1, b2, host.Shape("length"), 0.5 * (g1.OccupiedSize(host.type) + g2.OccupiedSize(host.type))});
      }
    for (int i = 1; i < n; ++i) {
      const Part& part = prog.PartOf(i);
      if (part.mass <= 0) continue;
      const double mass_kg = part.mass * 1e-6;  // mm³ × 1 g/cm³
      energy_.push_back({i, part.centre_of_mass, std::sqrt(mass_kg * opt.gravity / (1000.0 * opt.relaxation_datum_mm)),
                         -opt.relaxation_datum_mm});
    }
  }

  bool HasCycles() const { return !kin_.closing.empty() || !spacing_.empty(); }
  bool ClosesCycles() const { return !kin_.closing.empty(); }

  // Connection parameter values of start k (k = 0: box centre; else Halton).
  void SetStart(int k) {
    int dim = 0;
    static const int kPrimes[] = {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61, 67, 71, 73,
                                  79, 83, 89, 97, 101, 103, 107, 109, 113, 127, 131, 137, 139, 149, 151, 157, 163};
    const int np = sizeof(kPrimes) / sizeof(int);
    for (size_t b = 0; b < blocks_.size(); ++b) {
      const auto& specs = Spec(static_cast<int>(b));
      Block& s = blocks_[b];
      for (size_t i = 0; i < specs.size(); ++i) {
        if (specs[i].held) {
          s[i] = specs[i].init;
          continue;
        }
        // Start 0: the defaults (PARTS.md §1, spread where primitives are
        // shared); odd starts: Halton points over the whole box; even starts:
        // Halton points within ±1/8 of each range around the defaults (the
        // reference starts from its defaults; long chains close only near them).
        const double u = k == 0 ? -1 : Halton(k, kPrimes[dim++ % np]);
        const double w = specs[i].max - specs[i].min;
        s[i] = u < 0 ? specs[i].init
               : k % 2 == 1 ? specs[i].min + u * w
                            : std::clamp(specs[i].init + (u - 0.5) * w / 4, specs[i].min, specs[i].max);
      }
      if (kin_.sym_axis[b] >= 0) s[3] = k == 0 ? 0.0 : 360.0 * Halton(k, kPrimes[dim++ % np]);
    }
  }

  // Chain-by-chain initial guess (FabHacks, Table 5: for the reading nook
  // "the initial guesses are computed from optimizing individual chains in
  // the design"; PARTS.md §6: the reference's hand-set start vectors for it).
  // From the defaults (start 0):
  //  1. the chain from the environment to the target part — the spanning-tree
  //     connections on its path — minimises the step-1 target objective alone
  //     (no cycle terms), so the target part is placed first;
  //  2. each cycle-closing connection in program order closes its own cycle:
  //     its closure residual is minimised over its own parameters and those of
  //     the tree connections on its two parts' paths from the environment
  //     that no earlier chain moved, every earlier chain held where it was
  //     solved — each new connection starts from the already-solved chains.
  // Connections on no chain keep their defaults. Returns the chains solved.
  int SetChainStart() {
    SetStart(0);
    const int m = static_cast<int>(prog_.connections.size());
    const int n = static_cast<int>(prog_.instances.size());
    std::vector<int> edge_to(n, -1), parent(n, -1);  // tree connection placing each part
    for (const auto& [e, child] : kin_.tree) {
      edge_to[child] = e;
      const auto& c = prog_.connections[e];
      parent[child] = child == c.part_b ? c.part_a : c.part_b;
    }
    std::vector<char> solved(m, 0);
    auto take_path = [&](int part, Chain& chain) {
      for (int u = part; u >= 0 && edge_to[u] >= 0; u = parent[u])
        if (!solved[edge_to[u]]) chain.free[edge_to[u]] = 1;
    };
    auto run = [&](Chain& chain, bool target) {
      bool any = false;
      for (int e = 0; e < m; ++e) any = any || chain.free[e];
      if (!any) return false;
      Run(Phase::kObjective, target ? opt_.penalty_start : 1.0, nullptr, &chain);
      for (int e = 0; e < m; ++e) solved[e] = solved[e] || chain.free[e];
      return true;
    };
    int chains = 0;
    {
      Chain chain{std::vector<char>(m, 0), std::vector<double>(kin_.closing.size(), 0.0)};
      take_path(prog_.target, chain);
      chains += run(chain, true);
    }
    for (size_t k = 0; k < kin_.closing.size(); ++k) {
      const int e = kin_.closing[k];
      const auto& c = prog_.connections[e];
      Chain chain{std::vector<char>(m, 0), std::vector<double>(kin_.closing.size(), 0.0)};
      chain.closing_scale[k] = 1;
      take_path(c.part_a, chain);
      take_path(c.part_b, chain);
      chain.free[e] = 1;
      chains += run(chain, false);
    }
    return chains;
  }

  ceres::Solver::Summary Run(Phase phase, double sigma, std::unique_ptr<ceres::Problem>* keep = nullptr,
                             const Chain* chain = nullptr, int max_iterations = 0) {
    auto problem = std::make_unique<ceres::Problem>();
    Build(*problem, phase, sigma, chain);
    ceres::Solver::Options o;
    o.linear_solver_type = ceres::DENSE_QR;
    o.max_num_iterations = max_iterations > 0                ? max_iterations
                           : phase == Phase::kRelaxation ? opt_.relaxation_max_iterations
                                                         : opt_.max_iterations;
    o.num_threads = 1;
    o.logging_type = ceres::SILENT;
    o.function_tolerance = 1e-12;
    o.gradient_tolerance = 1e-12;
    o.parameter_tolerance = 1e-10;
    if (phase == Phase::kRelaxation) {
      // The energy landscape along a hanging chain is flat (see SolveOptions):
      // stop on the projected gradient and on the step, not on a relative
      // cost change (the cost carries the energy datum, so 1e-12 of it is
      // far above the energy differences still being resolved).
      o.function_tolerance = opt_.relaxation_function_tolerance;
      o.gradient_tolerance = opt_.relaxation_gradient_tolerance;
      o.parameter_tolerance = opt_.relaxation_parameter_tolerance;
    }
    StallCallback stall(opt_.stall_window, opt_.stall_slope, opt_.feasibility_tolerance);
    if (phase == Phase::kFeasibility) o.callbacks.push_back(&stall);
    RelaxationWindow window(blocks_, opt_.relaxation_window, opt_.relaxation_window_motion);
    if (phase == Phase::kRelaxation && opt_.relaxation_window > 0) {
      o.update_state_every_iteration = true;
      o.callbacks.push_back(&window);
    }

    ceres::Solver::Summary s;
    ceres::Solve(o, problem.get(), &s);
    // A held parameter's value is its held value (the gauge anchor may have
    // moved the unused block entry).
    for (size_t b = 0; b < blocks_.size(); ++b)
      for (int i = 0; i < internal::kParamBlock; ++i)
        if (kin_.held[b][i]) blocks_[b][i] = kin_.held_value[b][i];
    if (std::getenv("FABATLAS_ASSEMBLY_DEBUG"))
      std::fprintf(stderr, "phase %d sigma %g: %s (%s)\n", static_cast<int>(phase), sigma, s.BriefReport().c_str(),
                   s.message.c_str());
    if (keep) *keep = std::move(problem);
    return s;
  }

  // C = Σ‖g_j‖² + C_m at the current parameters (unit weights).
  double ConstraintResidual() {
    if (!HasCycles()) return 0;
    AssemblyResidual f = Residual(Phase::kFeasibility, 1.0);
    std::vector<double> r(f.NumResiduals());
    f(Pointers().data(), r.data());
    double c = 0;
    for (double x : r) c += x * x;
    return c;
  }

  std::vector<Eigen::Isometry3d> Poses() const {
    std::vector<const double*> ptr;
    for (const auto& b : blocks_) ptr.push_back(b.data());
    const auto p = kin_.Poses<double>(ptr.data());
    std::vector<Eigen::Isometry3d> out;
    for (const auto& m : p) {
      Eigen::Isometry3d t;
      t.matrix() = m;
      out.push_back(t);
    }
    return out;
  }

  // BOUNDED_AND_OPEN parameters at a bound with outward energy gradient
  // (FabHacks, 4.3.3).
  // With slide friction, a connector on a rod pushed against an open end
  // stays on when its load there is inside the friction cone.
  std::vector<std::string> FallsApart() {
    std::vector<std::string> out;
    if (opt_.slide_friction) EvaluateSlideLoads();
    const std::vector<double> grad = EnergyGradient();  // gravity + closure, not the gauge anchor
    for (size_t b = 0; b < blocks_.size(); ++b) {
      if (prog_.connections[b / 2].held_in_relaxation) continue;
      const auto& c = prog_.connections[b / 2];
      const std::string where = b % 2 == 0 ? prog_.instances[c.part_a].name + "." + c.primitive_a
                                           : prog_.instances[c.part_b].name + "." + c.primitive_b;
      const auto& specs = Spec(static_cast<int>(b));
      for (size_t i = 0; i < specs.size(); ++i) {
        const bool pinned =
            std::find(pinned_.begin(), pinned_.end(), std::make_pair(int(b), int(i))) != pinned_.end();
        if (specs[i].kind != ParamKind::kBoundedAndOpen || specs[i].held || (kin_.held[b][i] && !pinned)) continue;
        const SlideState* slide = FindSlide(static_cast<int>(b), static_cast<int>(i));
        if (slide && slide->angle_deg <= opt_.friction_angle_deg) continue;
        const double x = blocks_[b][i], g = grad[internal::kParamBlock * b + i];
        const double eps = 1e-6 * (specs[i].max - specs[i].min);
        if (std::getenv("FABATLAS_ASSEMBLY_DEBUG") && (x <= specs[i].min + eps || x >= specs[i].max - eps))
          std::fprintf(stderr, "at bound: %s.%s = %g, gradient %g\n", where.c_str(), specs[i].name.c_str(), x, g);
        if (x <= specs[i].min + eps && g > kForceTolerance && !specs[i].blocked_min)
          out.push_back(where + "." + specs[i].name + " at min");
        else if (x >= specs[i].max - eps && g < -kForceTolerance && !specs[i].blocked_max)
          out.push_back(where + "." + specs[i].name + " at max");
      }
    }
    return out;
  }

  // Static friction along rods (SolveOptions::slide_friction). Every t of a
  // rod, tube or edge on a connection the relaxation does not hold is a
  // slide; StickSlides holds each at its current value (the step-1 pose,
  // where the parts were put).
  void StickSlides() {
    slides_.clear();
    for (size_t b = 0; b < blocks_.size(); ++b) {
      const auto& c = prog_.connections[b / 2];
      if (c.held_in_relaxation) continue;
      const Primitive& p = b % 2 == 0 ? prog_.PrimitiveA(c) : prog_.PrimitiveB(c);
      if (p.type != PrimitiveType::kRod && p.type != PrimitiveType::kTube && p.type != PrimitiveType::kEdge) continue;
      const auto& specs = Spec(static_cast<int>(b));
      for (size_t i = 0; i < specs.size(); ++i)
        if (specs[i].name == "t" && !specs[i].held && !kin_.held[b][i]) {
          slides_.push_back({static_cast<int>(b), static_cast<int>(i)});
          SetStuck(slides_.back(), true);
        }
    }
  }

  // Lets go of every stuck slide whose load leaves the friction cone
  // (atan(axial/normal) > friction_angle_deg); returns how many.
  int ReleaseSlipping() {
    EvaluateSlideLoads();
    int released = 0;
    for (SlideState& sl : slides_)
      if (sl.stuck && sl.angle_deg > opt_.friction_angle_deg) {
        sl.slip_angle_deg = sl.angle_deg;
        SetStuck(sl, false);
        ++released;
      }
    return released;
  }

  // Active set of the relaxation (SolveOptions::relaxation_active_set; the
  // reference's active-set Newton): pins every bounded parameter that the
  // relaxation left at a bound with the energy pushing it out of its
  // interval; if none, unpins the pinned one the energy pushes back in
  // hardest (per mm or degree; one at a time, as an active-set method drops
  // one constraint per step — dropping all at once cycles on the reading
  // nook's ring links). A parameter held otherwise (base form, held
  // connection, stuck slide) is not touched. Returns how many changed; the
  // relaxation then runs again with the set held. Bounded
  // Levenberg-Marquardt alone creeps along a bound it keeps running into.
  int UpdateActiveSet() {
    const std::vector<double> grad = EnergyGradient();
    int pinned = 0;
    int worst = -1;  // the pinned parameter pushed back in hardest
    double worst_g = kForceTolerance;
    for (size_t b = 0; b < blocks_.size(); ++b) {
      if (prog_.connections[b / 2].held_in_relaxation) continue;
      const auto& specs = Spec(static_cast<int>(b));
      const auto units = Units(static_cast<int>(b));
      for (size_t i = 0; i < specs.size(); ++i) {
        if (specs[i].kind == ParamKind::kUnbounded || specs[i].held) continue;
        const double g = grad[internal::kParamBlock * b + i], x = blocks_[b][i];
        const double eps = 1e-6 * (specs[i].max - specs[i].min);
        const auto it = std::find(pinned_.begin(), pinned_.end(), std::make_pair(int(b), int(i)));
        if (it != pinned_.end()) {
          const double inward = (x <= specs[i].min + eps ? -g : g) / units[i];
          if (inward > worst_g) worst_g = inward, worst = static_cast<int>(it - pinned_.begin());
          continue;
        }
        if (kin_.held[b][i]) continue;
        const bool at_min = x <= specs[i].min + eps && g > kForceTolerance;
        const bool at_max = x >= specs[i].max - eps && g < -kForceTolerance;
        if (!at_min && !at_max) continue;
        blocks_[b][i] = at_min ? specs[i].min : specs[i].max;
        kin_.held[b][i] = true;
        kin_.held_value[b][i] = blocks_[b][i];
        pinned_.push_back({static_cast<int>(b), static_cast<int>(i)});
        ++pinned;
        if (std::getenv("FABATLAS_ASSEMBLY_DEBUG"))
          std::fprintf(stderr, "active set: pin %zu.%zu (%s) at %g, gradient %g\n", b, i, specs[i].name.c_str(),
                       blocks_[b][i], g);
      }
    }
    if (pinned > 0 || worst < 0) return pinned;
    const auto [b, i] = pinned_[worst];
    kin_.held[b][i] = false;
    pinned_.erase(pinned_.begin() + worst);
    if (std::getenv("FABATLAS_ASSEMBLY_DEBUG"))
      std::fprintf(stderr, "active set: unpin %d.%d, pushed in by %g per mm or degree\n", b, i, worst_g);
    return 1;
  }

  std::vector<SolveSummary::Slide> SlideReport() const {
    std::vector<SolveSummary::Slide> out;
    for (const SlideState& sl : slides_) {
      const auto& c = prog_.connections[sl.block / 2];
      const bool a = sl.block % 2 == 0;
      const std::string host = prog_.instances[a ? c.part_a : c.part_b].name + "." + (a ? c.primitive_a : c.primitive_b);
      const std::string guest = prog_.instances[a ? c.part_b : c.part_a].name + "." + (a ? c.primitive_b : c.primitive_a);
      out.push_back({host + "." + Spec(sl.block)[sl.index].name + " (" + guest + ")",
                     sl.stuck ? sl.angle_deg : sl.slip_angle_deg, sl.stuck});
    }
    return out;
  }

  std::vector<Block>& blocks() { return blocks_; }

  // Weight w (J per mm²) of the target term w·‖target error‖² in the
  // relaxation (SolveOptions::relaxation_target_weight); 0 removes it.
  void SetRelaxationTargetWeight(double w) { relax_target_scale_ = std::sqrt(2 * w); }

  // Step 2 starts here: the gauge anchor is the current parameters.
  void SetRelaxationAnchor() { anchor_ = blocks_; }

  // Adds `delta` to every parameter that is not held, clamped to the
  // parameter's bounds (SolvePerturbedRelaxation).
  void Perturb(double delta) {
    for (size_t b = 0; b < blocks_.size(); ++b) {
      const auto& specs = Spec(static_cast<int>(b));
      for (size_t i = 0; i < specs.size(); ++i) {
        if (specs[i].held) continue;
        double& x = blocks_[b][i];
        x += delta;
        if (specs[i].kind != ParamKind::kUnbounded) x = std::clamp(x, specs[i].min, specs[i].max);
      }
      if (kin_.sym_axis[b] >= 0) blocks_[b][3] += delta;
    }
  }

  // Analytic Jacobian of one phase against autodiff at the current parameters.
  internal::JacobianCheck CheckJacobian(Phase phase, double sigma) {
    internal::JacobianCheck out;
    AssemblyCost analytic(Residual(phase, sigma));
    if (analytic.num_residuals() == 0) return out;  // no cycles: nothing to close
    ceres::DynamicAutoDiffCostFunction<AssemblyResidual, 16> autodiff(new AssemblyResidual(Residual(phase, sigma)));
    for (size_t b = 0; b < blocks_.size(); ++b) autodiff.AddParameterBlock(internal::kParamBlock);
    autodiff.SetNumResiduals(analytic.num_residuals());
    const int nr = analytic.num_residuals();
    out.residuals = nr;
    out.parameters = internal::kParamBlock * static_cast<int>(blocks_.size());
    std::vector<std::vector<double>> j1(blocks_.size(), std::vector<double>(nr * internal::kParamBlock)), j2 = j1;
    std::vector<double*> p1, p2;
    for (size_t b = 0; b < blocks_.size(); ++b) p1.push_back(j1[b].data()), p2.push_back(j2[b].data());
    std::vector<double> r1(nr), r2(nr);
    const std::vector<double*> x = Pointers();
    analytic.Evaluate(x.data(), r1.data(), p1.data());
    autodiff.Evaluate(x.data(), r2.data(), p2.data());
    for (size_t b = 0; b < blocks_.size(); ++b)
      for (size_t i = 0; i < j1[b].size(); ++i) {
        out.max_error = std::max(out.max_error, std::abs(j1[b][i] - j2[b][i]));
        out.max_entry = std::max(out.max_entry, std::abs(j2[b][i]));
      }
    for (int i = 0; i < nr; ++i) out.max_residual_error = std::max(out.max_residual_error, std::abs(r1[i] - r2[i]));
    return out;
  }

 private:
  // mm per unit of each parameter of block b (slide parameters: the length
  // they run along; angles: 1, degrees).
  std::array<double, internal::kParamBlock> Units(int b) const {
    std::array<double, internal::kParamBlock> u{1, 1, 1, 1};
    const auto& c = prog_.connections[b / 2];
    const Primitive& p = b % 2 == 0 ? prog_.PrimitiveA(c) : prog_.PrimitiveB(c);
    const auto& specs = Spec(b);
    for (size_t i = 0; i < specs.size(); ++i) {
      if (specs[i].name == "t") u[i] = p.Shape("length");
      else if (specs[i].name == "t1") u[i] = p.Shape("width");
      else if (specs[i].name == "t2") u[i] = p.Shape("length");
    }
    return u;
  }

  void SetStuck(SlideState& sl, bool stuck) {
    sl.stuck = stuck;
    kin_.held[sl.block][sl.index] = stuck;
    kin_.held_value[sl.block][sl.index] = blocks_[sl.block][sl.index];
  }

  const SlideState* FindSlide(int b, int i) const {
    for (const SlideState& sl : slides_)
      if (sl.block == b && sl.index == i) return &sl;
    return nullptr;
  }

  // The load on each slide at the current parameters (J/mm). Along the axis:
  // the relaxation energy's gradient in t (gravity, the cycles' penalty and
  // the spacing of shared rods) over the length t runs along, evaluated as
  // if the slide were free — what friction (or an end) must hold. Across it:
  // the force F the connection transmits, less its component along the
  // slide's world direction a (dM/dt). F of a cycle-closing connection is its
  // penalty force 2σ_r·g (g the position residual, mm); F of a tree
  // connection holds up the subtree below it: minus the sum of its parts'
  // weights m·g and of the penalty forces of cycles reaching into it.
  void EvaluateSlideLoads() {
    if (slides_.empty()) return;
    const int n = static_cast<int>(prog_.instances.size());
    const std::vector<Eigen::Isometry3d> pose = Poses();
    std::vector<Eigen::Vector3d> force(n, Eigen::Vector3d::Zero());
    for (int i = 1; i < n; ++i) force[i].z() = -std::max(0.0, prog_.PartOf(i).mass) * 1e-6 * opt_.gravity / 1000;
    std::vector<Eigen::Vector3d> closing_force(prog_.connections.size(), Eigen::Vector3d::Zero());
    for (int e : kin_.closing) {
      const auto& c = prog_.connections[e];
      Mat4<double> ma, mb;
      kin_.Frames<double>(e, blocks_[2 * e].data(), blocks_[2 * e + 1].data(), ma, mb);
      const Eigen::Vector3d pa = (pose[c.part_a].matrix() * ma * kin_.align[e]).topRightCorner<3, 1>();
      const Eigen::Vector3d pb = (pose[c.part_b].matrix() * mb).topRightCorner<3, 1>();
      closing_force[e] = 2 * opt_.relaxation_penalty * (pa - pb);  // on part b, towards a
      force[c.part_b] += closing_force[e];
      force[c.part_a] -= closing_force[e];
    }
    // Gradient of the relaxation energy with the slides free.
    std::vector<char> was_held;
    for (const SlideState& sl : slides_) {
      was_held.push_back(kin_.held[sl.block][sl.index]);
      kin_.held[sl.block][sl.index] = false;
    }
    AssemblyCost cost(Residual(Phase::kRelaxation, opt_.relaxation_penalty));
    std::vector<double> r(cost.num_residuals());
    std::vector<std::vector<double>> jac(blocks_.size());
    std::vector<double*> jp(blocks_.size(), nullptr);
    for (const SlideState& sl : slides_) {
      jac[sl.block].resize(r.size() * internal::kParamBlock);
      jp[sl.block] = jac[sl.block].data();
    }
    const std::vector<double*> x = Pointers();
    cost.Evaluate(x.data(), r.data(), jp.data());
    for (size_t k = 0; k < slides_.size(); ++k) kin_.held[slides_[k].block][slides_[k].index] = was_held[k];

    std::vector<int> parent(n, -1), tree_edge(prog_.connections.size(), -1);
    for (const auto& [e, child] : kin_.tree) {
      const auto& c = prog_.connections[e];
      parent[child] = child == c.part_b ? c.part_a : c.part_b;
      tree_edge[e] = child;
    }
    for (SlideState& sl : slides_) {
      double grad = 0;
      for (size_t k = 0; k < r.size(); ++k) grad += jac[sl.block][k * internal::kParamBlock + sl.index] * r[k];
      sl.axial = std::abs(grad) / Units(sl.block)[sl.index];
      const int e = sl.block / 2;
      const auto& c = prog_.connections[e];
      const Primitive& p = sl.block % 2 == 0 ? prog_.PrimitiveA(c) : prog_.PrimitiveB(c);
      const int host = sl.block % 2 == 0 ? c.part_a : c.part_b;
      double xs[internal::kParamBlock];
      kin_.Effective<double>(sl.block, blocks_[sl.block].data(), xs);
      const FrameDerivatives fd = ConnectorFrameDerivatives(
          sl.block % 2 == 0 ? kin_.base_a[e] : kin_.base_b[e], p, xs, kin_.sym_axis[sl.block]);
      const Eigen::Vector3d dir = (pose[host].linear() * fd.d[sl.index].topRightCorner<3, 1>()).normalized();
      Eigen::Vector3d f = closing_force[e];
      if (tree_edge[e] >= 0) {
        f.setZero();
        for (int i = 1; i < n; ++i) {
          bool below = false;
          for (int u = i; u >= 0 && !below; u = parent[u]) below = u == tree_edge[e];
          if (below) f -= force[i];
        }
      }
      sl.normal = (f - f.dot(dir) * dir).norm();
      sl.angle_deg = std::atan2(sl.axial, sl.normal) * 180 / M_PI;
      if (std::getenv("FABATLAS_ASSEMBLY_DEBUG"))
        std::fprintf(stderr, "slide %d.%d%s: axial %.6g (|F.a| %.6g), normal %.6g J/mm, %.2f deg, t = %g\n",
                     sl.block, sl.index, sl.stuck ? " (held)" : "", sl.axial, std::abs(f.dot(dir)), sl.normal,
                     sl.angle_deg, blocks_[sl.block][sl.index]);
    }
  }

  // Gradient of the relaxation energy (gravity, closures, spacing; not the
  // gauge anchor) in every parameter, pinned ones included (J per unit).
  std::vector<double> EnergyGradient() {
    for (const auto& [b, i] : pinned_) kin_.held[b][i] = false;
    AssemblyCost cost(Residual(Phase::kRelaxation, opt_.relaxation_penalty));
    std::vector<double> r(cost.num_residuals());
    std::vector<std::vector<double>> jac(blocks_.size(), std::vector<double>(r.size() * internal::kParamBlock));
    std::vector<double*> jp;
    for (auto& j : jac) jp.push_back(j.data());
    const std::vector<double*> x = Pointers();
    cost.Evaluate(x.data(), r.data(), jp.data());
    for (const auto& [b, i] : pinned_) kin_.held[b][i] = true;
    std::vector<double> grad(blocks_.size() * internal::kParamBlock, 0.0);
    for (size_t b = 0; b < blocks_.size(); ++b)
      for (int i = 0; i < internal::kParamBlock; ++i)
        for (size_t k = 0; k < r.size(); ++k) grad[internal::kParamBlock * b + i] += jac[b][k * internal::kParamBlock + i] * r[k];
    return grad;
  }

  const std::vector<ParamSpec>& Spec(int b) const {
    const auto& c = prog_.connections[b / 2];
    return b % 2 == 0 ? c.params_a : c.params_b;
  }
  std::vector<double*> Pointers() {
    std::vector<double*> ptr;
    for (auto& b : blocks_) ptr.push_back(b.data());
    return ptr;
  }

  AssemblyResidual Residual(Phase phase, double sigma) const {
    AssemblyResidual f;
    f.kin = &kin_;
    f.phase = phase;
    f.closure_weight = phase == Phase::kFeasibility ? 1.0
                       : phase == Phase::kObjective ? std::sqrt(sigma)
                                                    : std::sqrt(2 * sigma);
    f.rot_scale = opt_.rotation_scale_mm;
    f.target_rot_scale = prog_.target_match_rotation ? opt_.target_mm_per_rad : 0.0;
    if (phase == Phase::kRelaxation) f.relax_target_scale = relax_target_scale_;
    f.spacing = spacing_;
    f.energy = energy_;
    f.target = &target_;
    return f;
  }

  void Build(ceres::Problem& problem, Phase phase, double sigma, const Chain* chain = nullptr) {
    AssemblyResidual f = Residual(phase, sigma);
    if (chain) f.closing_scale = chain->closing_scale;
    problem.AddResidualBlock(new AssemblyCost(std::move(f)), nullptr, Pointers());
    for (size_t b = 0; b < blocks_.size(); ++b) {
      const auto& c = prog_.connections[b / 2];
      double* s = blocks_[b].data();
      if (chain && !chain->free[b / 2]) {
        problem.SetParameterBlockConstant(s);
        continue;
      }
      const auto& specs = Spec(static_cast<int>(b));
      for (size_t i = 0; i < specs.size(); ++i)
        if (specs[i].kind != ParamKind::kUnbounded && !specs[i].held) {
          problem.SetParameterLowerBound(s, static_cast<int>(i), specs[i].min);
          problem.SetParameterUpperBound(s, static_cast<int>(i), specs[i].max);
        }
      // A clip clamps its partner: both sides of a clip connection are held
      // during relaxation, as are is_fixed connections (PARTS.md §1.10).
      const bool hold = phase == Phase::kRelaxation && c.held_in_relaxation;
      if (hold) problem.SetParameterBlockConstant(s);
      else if (phase == Phase::kRelaxation && opt_.relaxation_anchor_stiffness > 0)
        problem.AddResidualBlock(new AnchorCost(anchor_[b], opt_.relaxation_anchor_stiffness, Units(b)), nullptr, s);
    }
  }

  const Program& prog_;
  const SolveOptions& opt_;
  Kinematics kin_;
  std::vector<Block> blocks_;
  std::vector<SpacingTerm> spacing_;
  std::vector<EnergyTerm> energy_;
  TargetForm target_;
  std::vector<Block> anchor_;                       // gauge anchor of the relaxation
  std::vector<SlideState> slides_;                  // static friction along rods (StickSlides)
  double relax_target_scale_ = 0;                   // SetRelaxationTargetWeight
  std::vector<std::pair<int, int>> pinned_;         // active set: (block, index) held at a bound
  static constexpr double kForceTolerance = 1e-9;   // J per unit
};

void TargetErrors(const Program& prog, const Eigen::Isometry3d& pose, double& mm, double& deg) {
  TargetForm::Of(prog).Errors(pose.matrix(), mm, deg);
}

// Resting contacts (IsRestingContact: a surface standing on a surface, a
// roll on a rod; the side in its base form rests on the other). The
// reference glues them; a real part on a support slides off when the support
// tilts beyond the friction angle (a surface's normal from the vertical, a
// rod's axis from the horizontal), and a part standing on a surface tips over
// when the vertical through the centre of mass of it and everything it
// carries leaves its footprint (the small surface's W × L rectangle; the
// stands-on-a-flat-surface test of Fab Forms). Each is reported.
std::vector<std::string> RestingFailures(const Program& prog, const std::vector<Eigen::Isometry3d>& poses,
                                         double friction_angle_deg) {
  std::vector<std::string> out;
  const int n = static_cast<int>(prog.instances.size());
  std::vector<int> parent(n, -1);
  for (const auto& c : prog.connections)
    if (!c.closing) parent[c.part_b] = c.part_a;
  for (const auto& c : prog.connections) {
    if (!IsRestingContact(c.key)) continue;
    const bool a_rests = !c.params_a.empty() && c.params_a[0].held;
    const int part = a_rests ? c.part_a : c.part_b, support_part = a_rests ? c.part_b : c.part_a;
    if (part == 0) continue;
    const Primitive& foot = a_rests ? prog.PrimitiveA(c) : prog.PrimitiveB(c);
    const Primitive& support = a_rests ? prog.PrimitiveB(c) : prog.PrimitiveA(c);
    const Eigen::Vector3d axis = (poses[support_part] * ToIsometry(support.frame)).linear().col(2);
    const double tilt = support.type == PrimitiveType::kSurface
                            ? std::acos(std::clamp(std::abs(axis.z()), 0.0, 1.0)) * 180 / M_PI
                            : std::asin(std::clamp(std::abs(axis.z()), 0.0, 1.0)) * 180 / M_PI;
    const std::string name = prog.instances[part].name + "." + foot.name;
    if (tilt > friction_angle_deg) {
      out.push_back(name + " slides off (support tilted " + std::to_string(static_cast<int>(std::lround(tilt))) +
                    " deg)");
      continue;
    }
    if (foot.type != PrimitiveType::kSurface) continue;
    // Mass and centre of mass of the resting part and its subtree.
    double m = 0;
    Eigen::Vector3d com = Eigen::Vector3d::Zero();
    for (int i = 1; i < n; ++i) {
      bool below = false;
      for (int u = i; u > 0; u = parent[u])
        if (u == part) below = true;
      if (!below) continue;
      const Part& p = prog.PartOf(i);
      m += p.mass;
      com += p.mass * (poses[i] * p.centre_of_mass);
    }
    if (m <= 0) continue;
    com /= m;
    const Eigen::Isometry3d f = poses[part] * ToIsometry(foot.frame);
    // Where the vertical through the centre of mass meets the footprint's plane.
    const Eigen::Vector3d normal = f.linear().col(2), down(0, 0, -1);
    const double along = normal.dot(down);
    bool outside = std::abs(along) < 1e-9;
    if (!outside) {
      const double s = normal.dot(f.translation() - com) / along;
      const Eigen::Vector3d local = f.inverse() * (com + s * down);
      outside = std::abs(local.x()) > foot.Shape("length") / 2 || std::abs(local.y()) > foot.Shape("width") / 2;
    }
    if (outside) out.push_back(name + " tips over (centre of mass outside its footprint)");
  }
  return out;
}

double Since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

internal::JacobianCheck internal::CheckJacobian(const Program& program, int start, int phase,
                                                const SolveOptions& options) {
  Solver solver(program, options);
  solver.SetStart(start);
  const Phase p = static_cast<Phase>(phase);
  return solver.CheckJacobian(p, p == Phase::kObjective    ? options.penalty_start
                                 : p == Phase::kRelaxation ? options.relaxation_penalty
                                                           : 1.0);
}

namespace {
// Relaxation runs after which the active set is no longer updated (each
// update pins or unpins at least one parameter; a guard against cycling).
constexpr int kMaxRelaxationRuns = 400;
constexpr int kActiveSetRound = 1000;  // iterations per round of an active-set relaxation

SolveSummary Solve(const Program& prog, const SolveOptions& opt, double perturbation) {
  const auto t0 = std::chrono::steady_clock::now();
  SolveSummary out;
  const PrecheckSummary pre = Precheck(prog);
  out.precheck_seconds = Since(t0);
  for (const auto& i : pre.issues) out.messages.push_back(i.message);
  out.prechecks_passed = pre.ok;
  auto finish = [&]() {
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return out;
  };
  if (!pre.ok) return finish();

  Solver solver(prog, opt);
  std::vector<Block> best;
  double best_obj = std::numeric_limits<double>::infinity();
  int objective_starts = 0;
  std::vector<Block> closest;  // infeasible: the start that came closest to closing
  double closest_c = std::numeric_limits<double>::infinity();
  for (int k = 0; k < opt.restarts; ++k) {
    ++out.starts_tried;
    const auto tf = std::chrono::steady_clock::now();
    if (k == opt.chain_start && solver.ClosesCycles()) solver.SetChainStart();
    else solver.SetStart(k);
    if (solver.ConstraintResidual() >= opt.feasibility_tolerance) solver.Run(Phase::kFeasibility, 1.0);
    const double c = solver.ConstraintResidual();
    out.feasibility_seconds += Since(tf);
    if (c >= opt.feasibility_tolerance) {
      if (c < closest_c) closest_c = c, closest = solver.blocks();
      continue;
    }
    if (!out.feasible) out.feasibility_starts = k + 1;
    out.feasible = true;
    const auto to = std::chrono::steady_clock::now();
    // Step 1: user objective with penalty σ doubling (FabHacks, 4.3.3).
    double sigma = opt.penalty_start;
    for (int d = 0; d <= (solver.HasCycles() ? opt.penalty_doublings : 0); ++d, sigma *= 2) {
      solver.Run(Phase::kObjective, sigma);
      if (solver.ConstraintResidual() < opt.feasibility_tolerance) break;
    }
    double mm, deg;
    TargetErrors(prog, solver.Poses()[prog.target], mm, deg);
    if (!prog.target_match_rotation) deg = 0;
    out.objective_seconds += Since(to);
    const double obj = mm * mm + std::pow(opt.target_mm_per_rad * deg * M_PI / 180, 2);
    if (obj < best_obj) {
      best_obj = obj;
      best = solver.blocks();
    }
    if (mm < opt.early_exit_mm && deg < 1.0) break;
    if (++objective_starts >= opt.objective_starts) break;
  }
  if (!out.feasible) {
    out.messages.push_back(prog.file + ": cycles do not close after " + std::to_string(out.starts_tried) + " starts");
    solver.blocks() = closest;
    out.constraint_residual = closest_c;
    out.poses = solver.Poses();
    return finish();
  }
  solver.blocks() = best;
  out.constraint_residual = solver.ConstraintResidual();
  out.step1_poses = solver.Poses();
  TargetErrors(prog, out.step1_poses[prog.target], out.step1_target_error_mm, out.step1_target_error_deg);
  if (opt.relax) {
    if (perturbation != 0) solver.Perturb(perturbation);
    solver.SetRelaxationAnchor();
    const auto tr = std::chrono::steady_clock::now();
    // Static friction along rods: relax with every slide held, let go of
    // those whose load leaves the friction cone and relax again from there,
    // until every slide still held is inside it (at most one more relaxation
    // per slide: a slide let go is not held again).
    if (opt.slide_friction) solver.StickSlides();
    // Optionally the reference implementation's continuation first
    // (SolveOptions::relaxation_target_weight): the target term w·‖error‖²,
    // w divided by 10 at every convergence, the slides held throughout;
    // then the energy alone.
    for (double w = opt.relaxation_target_weight; w > opt.relaxation_target_weight_end; w *= 0.1) {
      solver.SetRelaxationTargetWeight(w);
      const ceres::Solver::Summary rs = solver.Run(Phase::kRelaxation, opt.relaxation_penalty);
      out.relaxation_iterations += static_cast<int>(rs.iterations.size()) - 1;
      ++out.relaxation_runs;
    }
    solver.SetRelaxationTargetWeight(0);
    // With the active set, step 2 runs in rounds of at most
    // kActiveSetRound iterations and updates the set after each, so a
    // parameter that runs into a bound is held there within a round instead
    // of LM creeping along it; a round that ends at its cap with the set
    // unchanged goes on, up to relaxation_max_iterations in all since the
    // last change.
    int since_change = 0;
    for (;;) {
      const ceres::Solver::Summary rs = solver.Run(Phase::kRelaxation, opt.relaxation_penalty, nullptr, nullptr,
                                                   opt.relaxation_active_set ? kActiveSetRound : 0);
      out.relaxation_termination = ceres::TerminationTypeToString(rs.termination_type);
      out.relaxation_iterations += static_cast<int>(rs.iterations.size()) - 1;
      ++out.relaxation_runs;
      if (opt.relaxation_active_set && out.relaxation_runs < kMaxRelaxationRuns) {
        if (solver.UpdateActiveSet() > 0) {
          since_change = 0;
          continue;
        }
        since_change += static_cast<int>(rs.iterations.size()) - 1;
        if (rs.termination_type == ceres::NO_CONVERGENCE && since_change < opt.relaxation_max_iterations) continue;
      }
      if (!opt.slide_friction || solver.ReleaseSlipping() == 0) break;
      since_change = 0;
    }
    out.relaxation_seconds = Since(tr);
    out.falls_apart = solver.FallsApart();
    out.slides = solver.SlideReport();
  }
  out.poses = solver.Poses();
  for (size_t e = 0; e < prog.connections.size(); ++e) {
    std::vector<double> s;
    const auto& c = prog.connections[e];
    for (size_t i = 0; i < c.params_a.size(); ++i)
      s.push_back(c.params_a[i].held ? c.params_a[i].init : solver.blocks()[2 * e][i]);
    for (size_t i = 0; i < c.params_b.size(); ++i)
      s.push_back(c.params_b[i].held ? c.params_b[i].init : solver.blocks()[2 * e + 1][i]);
    out.params.push_back(s);
  }
  TargetErrors(prog, out.poses[prog.target], out.final_target_error_mm, out.final_target_error_deg);
  {
    const Eigen::Matrix4d off = prog.TargetOffset();
    const Eigen::Matrix4d q1 = out.step1_poses[prog.target].matrix() * off, q2 = out.poses[prog.target].matrix() * off;
    out.relax_displacement_mm = (q2.topRightCorner<3, 1>() - q1.topRightCorner<3, 1>()).norm();
    out.relax_rotation_deg = RotationAngleDeg(q2.topLeftCorner<3, 3>(), q1.topLeftCorner<3, 3>());
  }
  if (opt.relax) {
    const auto tipped = RestingFailures(prog, out.poses, opt.friction_angle_deg);
    out.falls_apart.insert(out.falls_apart.end(), tipped.begin(), tipped.end());
  }
  // FabHacks Sec. 4.3.3: the assembly is reported as falling apart when a
  // connector slides off (above) — and, for a part resting on another, when
  // it slides off or tips over. Relaxation motion alone is not a failure (in the paper's
  // frictionless model the demo slides its S-hook to the end of the hanger bar and works).
  out.stable = opt.relax && out.falls_apart.empty();
  out.target_reached = out.final_target_error_mm <= opt.target_tolerance_mm &&
                       (!prog.target_match_rotation || out.final_target_error_deg <= opt.target_tolerance_deg);
  return finish();
}

}  // namespace

SolveSummary SolveAssembly(const Program& prog, const SolveOptions& opt) { return Solve(prog, opt, 0.0); }

SolveSummary internal::SolvePerturbedRelaxation(const Program& prog, double delta, const SolveOptions& opt) {
  return Solve(prog, opt, delta);
}

}  // namespace fabatlas::assembly
