// Internal: the prototype as solver variables, part poses per configuration
// and the linear constraints of its functional relationships.
//
// Variables: 6 per cuboid (parts, then cavities; x0 x1 y0 y1 z0 z1 in the base
// configuration), then the free joint values (free slides, free in-plane
// offsets of double-pivot children). With every joint angle fixed per
// configuration, a part's pose is a constant rotation and a translation that
// is affine in the variables, so every box, face and relationship constraint
// below is linear (Koo et al. Sec. 5: "a set of equality and inequality
// constraints that are linear").
#pragma once

#include <string>
#include <vector>

#include "affine.h"
#include "fabatlas/prototype/prototype.h"

namespace fabatlas::prototype::internal {

struct Pose {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Affine3 t;
};

struct Box {
  Affine lo[3], hi[3];
};

struct Face {
  std::string name;
  int axis = 0;  // normal axis in the frame
  Affine plane;  // coordinate of the plane along `axis`
  Box box;       // lo[axis] = hi[axis] = plane
};

// g == 0 (eq) or g >= 0.
struct LinearConstraint {
  Affine g;
  bool eq = true;
  int group = 0;
  std::string label;
};

Eigen::Matrix3d AxisRotation(int axis, double degrees);  // exact for multiples of 90

// A cuboid's six variables in order (the variables above).
inline constexpr const char* kCoord[6] = {"x0", "x1", "y0", "y1", "z0", "z1"};

class Model {
 public:
  explicit Model(const Prototype& p);

  const Prototype& proto;
  // Parts first (cuboid i = part i), then cavities, then pieces.
  std::vector<std::string> cuboid_names;  // "part", "part.cavity" or "part.piece"
  std::vector<int> cuboid_part;
  std::vector<bool> cuboid_solid;  // part or piece (not a cavity)
  std::vector<const Cuboid*> cuboids;
  int variables = 0;
  Eigen::VectorXd base, weight;         // target and weight of the deviation energy
  std::vector<std::string> free_names;  // "joint@config.k", variable = 6*cuboids + i

  int CuboidIndex(const std::string& name, const std::string& where) const;
  // `name` is a part: its solid cuboids; a piece or cavity: itself.
  std::vector<int> SolidsOf(const std::string& name, const std::string& where) const;
  // A slide's travel along its axis in configuration c (0 when not set).
  Affine SlideValue(const Joint& j, const Configuration& c) const;
  // Base coordinate refs for expressions: part.x0 .. part.z1, part.w/.d/.h
  // (extents), part.cx/.cy/.cz (centres), the same for part.cavity.*, and
  // parameters as constants.
  Affine Resolve(const std::string& name, const std::string& where) const;
  Affine ParseExpression(const std::string& text, const std::string& where) const;

  const Configuration& Config(const std::string& name) const;
  // Pose of a part in configuration c with every joint value scaled by s
  // (s = 1: the configuration; s in (0,1): along the motion from base).
  Pose PoseOf(int part, const Configuration& c, double s = 1) const;
  // A cuboid's box in configuration c, in the base frame of `frame_part`
  // moved into c (-1: world).
  Box BoxIn(int cuboid, const Configuration& c, int frame_part = -1) const;
  // "part.x0" or "part.cavity.y1" in configuration c (world frame). Throws
  // InputError when the face is not axis-aligned there.
  Face FaceIn(const std::string& ref, const Configuration& c, const std::string& where) const;

  // Every constraint with its group; groups[i] is "what (file:line:col)".
  void Build(std::vector<LinearConstraint>& out, std::vector<std::string>& groups) const;

 private:
  int FreeIndex(const std::string& key) const;
  Pose JointMotion(int joint, const Configuration& c, double s) const;
};

}  // namespace fabatlas::prototype::internal
