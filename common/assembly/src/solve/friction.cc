// Static friction along rods, tubes and edges in the relaxation
// (solve/solver.h, SolveOptions::slide_friction): slides held, their loads,
// and those let go when the load leaves the friction cone.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "assembly_cost.h"
#include "solver.h"

namespace fabatlas::assembly::internal {

// Static friction along rods (SolveOptions::slide_friction). Every t of a
// rod, tube or edge on a connection the relaxation does not hold is a
// slide; StickSlides holds each at its current value (the step-1 pose,
// where the parts were put).
void Solver::StickSlides() {
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
int Solver::ReleaseSlipping() {
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

std::vector<SolveSummary::Slide> Solver::SlideReport() const {
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

void Solver::SetStuck(SlideState& sl, bool stuck) {
  sl.stuck = stuck;
  kin_.held[sl.block][sl.index] = stuck;
  kin_.held_value[sl.block][sl.index] = blocks_[sl.block][sl.index];
}

const SlideState* Solver::FindSlide(int b, int i) const {
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
void Solver::EvaluateSlideLoads() {
  if (slides_.empty()) return;
  const int n = static_cast<int>(prog_.instances.size());
  const std::vector<Eigen::Isometry3d> pose = Poses();
  std::vector<Eigen::Vector3d> force(n, Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> closing_force(prog_.connections.size(), Eigen::Vector3d::Zero());
  PartForces(pose, force, closing_force);
  const std::vector<double> grad = SlideGradients();
  for (size_t k = 0; k < slides_.size(); ++k) {
    SlideState& sl = slides_[k];
    sl.axial = std::abs(grad[k]) / Units(sl.block)[sl.index];
    const int e = sl.block / 2;
    const auto& c = prog_.connections[e];
    const Primitive& p = sl.block % 2 == 0 ? prog_.PrimitiveA(c) : prog_.PrimitiveB(c);
    const int host = sl.block % 2 == 0 ? c.part_a : c.part_b;
    double xs[internal::kParamBlock];
    kin_.Effective<double>(sl.block, blocks_[sl.block].data(), xs);
    const FrameDerivatives fd =
        ConnectorFrameDerivatives(sl.block % 2 == 0 ? kin_.base_a[e] : kin_.base_b[e], p, xs, kin_.sym_axis[sl.block]);
    const Eigen::Vector3d dir = (pose[host].linear() * fd.d[sl.index].topRightCorner<3, 1>()).normalized();
    const Eigen::Vector3d f = SlideForce(e, force, closing_force);
    sl.normal = (f - f.dot(dir) * dir).norm();
    sl.angle_deg = std::atan2(sl.axial, sl.normal) * 180 / M_PI;
    if (std::getenv("FABATLAS_ASSEMBLY_DEBUG"))
      std::fprintf(stderr, "slide %d.%d%s: axial %.6g (|F.a| %.6g), normal %.6g J/mm, %.2f deg, t = %g\n", sl.block,
                   sl.index, sl.stuck ? " (held)" : "", sl.axial, std::abs(f.dot(dir)), sl.normal, sl.angle_deg,
                   blocks_[sl.block][sl.index]);
  }
}

// The weight of every part (force, J/mm) plus the penalty forces of the
// closing connections on their two parts; closing_force[e] is the force on
// part b of closing connection e, towards part a.
void Solver::PartForces(const std::vector<Eigen::Isometry3d>& pose, std::vector<Eigen::Vector3d>& force,
                        std::vector<Eigen::Vector3d>& closing_force) const {
  const int n = static_cast<int>(prog_.instances.size());
  for (int i = 1; i < n; ++i) force[i].z() = -std::max(0.0, prog_.PartOf(i).mass) * 1e-6 * opt_.gravity / 1000;
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
}

// The relaxation energy's gradient in each slide's parameter (J per unit),
// evaluated with the slides free.
std::vector<double> Solver::SlideGradients() {
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
  std::vector<double> out;
  for (const SlideState& sl : slides_) {
    double grad = 0;
    for (size_t k = 0; k < r.size(); ++k) grad += jac[sl.block][k * internal::kParamBlock + sl.index] * r[k];
    out.push_back(grad);
  }
  return out;
}

// The force connection e transmits: a closing connection's penalty force; a
// tree connection's holds up the subtree below it.
Eigen::Vector3d Solver::SlideForce(int e, const std::vector<Eigen::Vector3d>& force,
                                   const std::vector<Eigen::Vector3d>& closing_force) const {
  const int n = static_cast<int>(prog_.instances.size());
  std::vector<int> parent(n, -1), tree_edge(prog_.connections.size(), -1);
  for (const auto& [edge, child] : kin_.tree) {
    const auto& c = prog_.connections[edge];
    parent[child] = child == c.part_b ? c.part_a : c.part_b;
    tree_edge[edge] = child;
  }
  Eigen::Vector3d f = closing_force[e];
  if (tree_edge[e] >= 0) {
    f.setZero();
    for (int i = 1; i < n; ++i) {
      bool below = false;
      for (int u = i; u >= 0 && !below; u = parent[u]) below = u == tree_edge[e];
      if (below) f -= force[i];
    }
  }
  return f;
}

}  // namespace fabatlas::assembly::internal
