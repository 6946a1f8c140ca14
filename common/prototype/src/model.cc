// The prototype's model: variables, joint motions, part poses, boxes and
// faces per configuration (model.h; its constraints in build_constraints.cc).
#include "model.h"

#include <algorithm>
#include <cmath>

#include "fabatlas/error.h"

namespace fabatlas::prototype::internal {
Eigen::Matrix3d AxisRotation(int axis, double degrees) {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  a[axis] = 1;
  Eigen::Matrix3d r = Eigen::AngleAxisd(degrees * M_PI / 180, a).toRotationMatrix();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double v = r(i, j);
      for (double k : {-1.0, 0.0, 1.0})
        if (std::abs(v - k) < 1e-12) r(i, j) = k;
    }
  return r;
}

Model::Model(const Prototype& p) : proto(p) {
  for (std::size_t i = 0; i < p.parts.size(); ++i) {
    cuboid_names.push_back(p.parts[i].name);
    cuboid_part.push_back(static_cast<int>(i));
    cuboid_solid.push_back(true);
    cuboids.push_back(&p.parts[i].cuboid);
  }
  for (bool solid : {false, true})
    for (std::size_t i = 0; i < p.parts.size(); ++i)
      for (const Cuboid& c : solid ? p.parts[i].pieces : p.parts[i].cavities) {
        cuboid_names.push_back(c.name);
        cuboid_part.push_back(static_cast<int>(i));
        cuboid_solid.push_back(solid);
        cuboids.push_back(&c);
      }
  std::vector<double> guesses;
  for (const Configuration& c : p.configurations)
    for (const auto& [jn, v] : c.values) {
      const Joint& j = *std::find_if(p.joints.begin(), p.joints.end(), [&](const Joint& k) { return k.name == jn; });
      const Joint& first =
          *std::find_if(p.joints.begin(), p.joints.end(), [&](const Joint& k) { return k.child == j.child; });
      if (first.name != j.name) continue;  // a second double pivot on the same part: the first one places it
      if ((j.type == JointType::kSlide || j.type == JointType::kSlidingHinge) && v.slide == "free") {
        free_names.push_back(jn + "@" + c.name + ".s");
        guesses.push_back(v.slide_guess);
      }
      if (j.type == JointType::kDoublePivot && v.offset_free)
        for (int k = 0; k < 3; ++k)
          if (k != j.normal) {
            free_names.push_back(jn + "@" + c.name + "." + std::to_string(k));
            guesses.push_back(v.offset[k]);
          }
    }
  int nc = static_cast<int>(cuboids.size());
  variables = 6 * nc + static_cast<int>(free_names.size());
  base.resize(variables);
  weight.resize(variables);
  for (int c = 0; c < nc; ++c)
    for (int k = 0; k < 6; ++k) {
      base[6 * c + k] = cuboids[c]->box[k];
      weight[6 * c + k] = 1;
    }
  // Free joint values are not part geometry (Eq. 4 has only B and L); a weak
  // pull towards the user's arrangement makes the solution unique.
  for (std::size_t i = 0; i < guesses.size(); ++i) {
    base[6 * nc + i] = guesses[i];
    weight[6 * nc + i] = 1e-4;
  }
}

int Model::FreeIndex(const std::string& key) const {
  auto it = std::find(free_names.begin(), free_names.end(), key);
  return 6 * static_cast<int>(cuboids.size()) + static_cast<int>(it - free_names.begin());
}

int Model::CuboidIndex(const std::string& name, const std::string& where) const {
  for (std::size_t i = 0; i < cuboid_names.size(); ++i)
    if (cuboid_names[i] == name) return static_cast<int>(i);
  throw InputError(where + ": unknown part or cavity '" + name + "'");
}

std::vector<int> Model::SolidsOf(const std::string& name, const std::string& where) const {
  int c = CuboidIndex(name, where);
  if (c != cuboid_part[c]) return {c};
  std::vector<int> out;
  for (std::size_t i = 0; i < cuboids.size(); ++i)
    if (cuboid_part[i] == c && cuboid_solid[i]) out.push_back(static_cast<int>(i));
  return out;
}

Affine Model::SlideValue(const Joint& j, const Configuration& c) const {
  auto it = c.values.find(j.name);
  if (it == c.values.end()) return Affine::Const(0);
  if (it->second.slide == "free") return Affine::Var(FreeIndex(j.name + "@" + c.name + ".s"));
  return ParseExpression(it->second.slide, j.where);
}

Affine Model::Resolve(const std::string& name, const std::string& where) const {
  if (auto it = proto.parameters.find(name); it != proto.parameters.end()) return Affine::Const(it->second);
  auto dot = name.rfind('.');
  if (dot == std::string::npos) throw InputError(where + ": unknown name '" + name + "' (write part.x0, part.w, ...)");
  int c = CuboidIndex(name.substr(0, dot), where);
  std::string k = name.substr(dot + 1);
  for (int i = 0; i < 6; ++i)
    if (k == kCoord[i]) return Affine::Var(6 * c + i);
  const char* ext[3] = {"w", "d", "h"};
  const char* mid[3] = {"cx", "cy", "cz"};
  for (int i = 0; i < 3; ++i) {
    if (k == ext[i]) return Affine::Var(6 * c + 2 * i + 1) - Affine::Var(6 * c + 2 * i);
    if (k == mid[i]) return 0.5 * (Affine::Var(6 * c + 2 * i + 1) + Affine::Var(6 * c + 2 * i));
  }
  throw InputError(where + ": '" + k + "' is not x0 x1 y0 y1 z0 z1 w d h cx cy cz in '" + name + "'");
}

Affine Model::ParseExpression(const std::string& text, const std::string& where) const {
  return ParseAffine(
      text, [&](const std::string& n) { return Resolve(n, where); }, where);
}

const Configuration& Model::Config(const std::string& name) const {
  for (const auto& c : proto.configurations)
    if (c.name == name) return c;
  throw InputError(proto.file + ": unknown configuration '" + name + "'");
}

Pose Model::JointMotion(int ji, const Configuration& c, double s) const {
  const Joint& j = proto.joints[ji];
  JointValue v;
  auto it = c.values.find(j.name);
  bool set = it != c.values.end();
  if (set) v = it->second;
  Pose m;
  auto slide_value = [&]() -> Affine { return s * SlideValue(j, c); };
  auto rotate_about = [&](const Affine3& p) { m.t = Sub(p, Mul(m.R, p)); };
  auto edge = [&]() {
    Affine3 p;
    int k = 0;
    for (int ax = 0; ax < 3; ++ax) {
      if (ax == j.axis) continue;
      p[ax] = Resolve(j.at[k++][0], j.where);
    }
    return p;
  };
  switch (j.type) {
    case JointType::kHinge:
      m.R = AxisRotation(j.axis, s * v.angle);
      rotate_about(edge());
      break;
    case JointType::kSlide:
      m.t[j.axis] = slide_value();
      break;
    case JointType::kSlidingHinge:
      m.R = AxisRotation(j.axis, s * v.angle);
      rotate_about(edge());
      m.t[j.slide_axis] = m.t[j.slide_axis] + slide_value();
      break;
    case JointType::kDoublePivot: {
      m.R = AxisRotation(j.normal, s * v.angle);
      int cu = CuboidIndex(j.child, j.where);
      Affine3 centre;
      for (int ax = 0; ax < 3; ++ax)
        centre[ax] = 0.5 * (Affine::Var(6 * cu + 2 * ax) + Affine::Var(6 * cu + 2 * ax + 1));
      rotate_about(centre);
      if (set)
        for (int ax = 0; ax < 3; ++ax) {
          Affine o = (v.offset_free && ax != j.normal)
                         ? Affine::Var(FreeIndex(j.name + "@" + c.name + "." + std::to_string(ax)))
                         : Affine::Const(v.offset[ax]);
          m.t[ax] = m.t[ax] + s * o;
        }
      break;
    }
  }
  return m;
}

Pose Model::PoseOf(int part, const Configuration& c, double s) const {
  const std::string& name = proto.parts[part].name;
  for (std::size_t ji = 0; ji < proto.joints.size(); ++ji) {
    if (proto.joints[ji].child != name) continue;
    Pose m = JointMotion(static_cast<int>(ji), c, s);
    Pose pp = PoseOf(proto.PartIndex(proto.joints[ji].parent), c, s);
    Pose out;
    out.R = pp.R * m.R;
    out.t = Add(Mul(pp.R, m.t), pp.t);
    return out;
  }
  return Pose{};
}

Box Model::BoxIn(int cuboid, const Configuration& c, int frame_part) const {
  Pose p = PoseOf(cuboid_part[cuboid], c);
  Eigen::Matrix3d R = p.R;
  Affine3 t = p.t;
  if (frame_part >= 0) {
    Pose f = PoseOf(frame_part, c);
    R = f.R.transpose() * p.R;
    t = Mul(f.R.transpose(), Sub(p.t, f.t));
  }
  Affine3 centre, half;
  for (int ax = 0; ax < 3; ++ax) {
    centre[ax] = 0.5 * (Affine::Var(6 * cuboid + 2 * ax) + Affine::Var(6 * cuboid + 2 * ax + 1));
    half[ax] = 0.5 * (Affine::Var(6 * cuboid + 2 * ax + 1) - Affine::Var(6 * cuboid + 2 * ax));
  }
  Affine3 cw = Add(Mul(R, centre), t);
  Affine3 hw = Mul(R.cwiseAbs(), half);
  Box b;
  for (int ax = 0; ax < 3; ++ax) {
    b.lo[ax] = cw[ax] - hw[ax];
    b.hi[ax] = cw[ax] + hw[ax];
  }
  return b;
}

Face Model::FaceIn(const std::string& ref, const Configuration& c, const std::string& where) const {
  auto dot = ref.rfind('.');
  if (dot == std::string::npos)
    throw InputError(where + ": '" + ref + "' is not a face (part.x0, part.cavity.y1, ...)");
  int cu = CuboidIndex(ref.substr(0, dot), where);
  std::string k = ref.substr(dot + 1);
  int coord = -1;
  for (int i = 0; i < 6; ++i)
    if (k == kCoord[i]) coord = i;
  if (coord < 0) throw InputError(where + ": '" + ref + "': a face is x0 x1 y0 y1 z0 z1");
  Pose p = PoseOf(cuboid_part[cu], c);
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  n[coord / 2] = coord % 2 ? 1 : -1;
  Eigen::Vector3d rn = p.R * n;
  Face f;
  f.name = ref;
  f.axis = -1;
  for (int ax = 0; ax < 3; ++ax)
    if (std::abs(std::abs(rn[ax]) - 1) < 1e-9) f.axis = ax;
  if (f.axis < 0)
    throw InputError(where + ": face " + ref + " is not axis-aligned in configuration '" + c.name +
                     "' (use multiples of 90 degrees there)");
  f.box = BoxIn(cu, c);
  f.plane = rn[f.axis] > 0 ? f.box.hi[f.axis] : f.box.lo[f.axis];
  f.box.lo[f.axis] = f.box.hi[f.axis] = f.plane;
  return f;
}

}  // namespace fabatlas::prototype::internal
