// Resting contacts after the relaxation (solve/resting_contacts.h).
#include "resting_contacts.h"

#include <algorithm>
#include <cmath>

namespace fabatlas::assembly::internal {

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

}  // namespace fabatlas::assembly::internal
