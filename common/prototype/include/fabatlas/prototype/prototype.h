// fabatlas/prototype/prototype.h — works-like prototypes (Koo et al., docs/references.md): cuboid
// parts, joints, configurations and functional relationships, read from YAML
// (docs/prototype.md).
//
// Coordinates are millimetres, z up, angles degrees. A cuboid is stored as its
// base-configuration box [x0, x1, y0, y1, z0, z1] (Koo et al. Sec. 6: "left,
// right, bottom, top, near and far coordinates"). Numbers in a file may be
// expressions over the file's `parameters`, which callers can override.
#pragma once

#include <array>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "fabatlas/vec3.h"

namespace fabatlas::prototype {

struct Cuboid {
  std::string name;             // part name, "part.cavity" for a cavity, "part.piece" for a piece
  std::array<double, 6> box{};  // x0 x1 y0 y1 z0 z1, base configuration
  std::string open;             // cavity only: face ("y0", ...) that lies on the part's face
  std::vector<int> held;        // piece or cavity: coordinates (0..5) held at their base value
  // Piece only (a further solid cuboid of the part, Koo et al. Sec. 3: "each
  // part consists of one or more axis-aligned connected cuboids"): the cuboid
  // it is connected to ("part" or "part.piece", default the part's first
  // cuboid) and coordinates kept equal to that cuboid's (e.g. "x0").
  std::string on;
  std::vector<int> align;
};

struct Part {
  std::string name;
  Cuboid cuboid;                 // the part's first cuboid (joints attach to it)
  std::vector<Cuboid> pieces;    // further solid cuboids, connected to it, move with the part
  std::vector<Cuboid> cavities;  // user cavities, move with the part
  std::vector<int> held;         // coordinates (0..5) held at their base value (a user edit)
  double min_size = 1.0;         // every extent >= this, mm
  std::string where;             // file:line:col
};

enum class JointType { kHinge, kSlide, kSlidingHinge, kDoublePivot };

// A joint moves `child` relative to `parent` (Koo et al. Sec. 3, Fig. 2).
struct Joint {
  std::string name;
  JointType type = JointType::kHinge;
  std::string child, parent;
  int axis = 2;        // hinge / sliding hinge rotation axis; slide direction
  int slide_axis = 0;  // sliding hinge: translation direction
  // Slide: the child's and the parent's faces the rails run between
  // ("drawer.z0", "body.z1"); held coplanar, and the child stays on the parent
  // along the slide in every configuration. Empty: the child slides tightly
  // in the parent (a fit inside), no rails (Koo et al. Sec. 7).
  std::vector<std::string> on;
  // Hinge edge: for the two axes other than `axis` (in increasing order), the
  // coordinate refs ("door.x0"); the first of each list places the edge, the
  // others are held equal to it (the joint stays attached).
  std::vector<std::vector<std::string>> at;
  // Double pivot: the pivot plane's normal axis, the face side both parts
  // share ("x0" or "x1" of the child), and the initial pivot positions as
  // fractions of each cuboid's extent along the two in-plane axes.
  int normal = 0;
  std::string face = "x0";
  std::array<double, 2> pivot_child{0.5, 0.5}, pivot_parent{0.5, 0.5};
  std::string where;
};

// A joint's pose in one configuration (Koo et al.: j(θ)).
struct JointValue {
  double angle = 0;         // degrees (hinge, sliding hinge, double pivot)
  std::string slide = "0";  // mm, an expression over coordinates; "free" = solved for
  double slide_guess = 0;   // free slide: the value it is kept near
  // Double pivot: translation of the child (about its centre, after the
  // rotation); `offset_free` components are solved for and kept near `offset`.
  Vec3 offset{0, 0, 0};
  bool offset_free = false;
};

struct Configuration {
  std::string name;
  std::map<std::string, JointValue> values;  // joint name -> value; others at 0
};

enum class RelationType { kCover, kFit, kSupport, kFlush, kGeometric };

struct Relationship {
  RelationType type = RelationType::kCover;
  std::string name;
  std::string configuration = "base";
  std::vector<std::string> a, b;  // cover: covering/covered faces; fit: inner parts, {outer}; flush: 2 faces
  std::vector<std::pair<std::string, std::string>> pairs;  // support: (supporting face, supported face)
  std::vector<std::string> just;                           // cover: "true"; fit: sides that just fit ("x0", ...)
  std::vector<int> axes{0, 1, 2};                          // fit: axes that are constrained ("fit partially inside")
  double min_overlap = 1.0;                                // support: faces overlap by at least this, mm
  std::string expression;                                  // geometric: "lhs == rhs" / "<=" / ">="
  std::string where;
};

struct Fabrication {
  double voxel = 0.5;  // level-set voxel, mm
  double gap = 1.0;    // print gap between touching parts and around moving joint pieces, mm
};

struct Prototype {
  std::string file, name;
  std::map<std::string, double> parameters;
  std::vector<Part> parts;
  std::vector<Joint> joints;
  std::vector<Configuration> configurations;  // "base" first (all joints at 0)
  std::vector<Relationship> relationships;
  Fabrication fabrication;

  int PartIndex(const std::string& name) const;  // -1 if absent
};

// A discrete edit (Koo et al. Sec. 6, the jewellery box of Sec. 8): the
// prototype without `part`, the parts hanging from it by joints, their joints
// and configuration values; relationships lose the faces and parts of the
// removed parts and are dropped when nothing of one side is left (a flush or
// geometric constraint naming a removed part is dropped). Solve the result
// to update the remaining parts. Throws InputError for an unknown part.
Prototype RemovePart(const Prototype& p, const std::string& part);

// Reads a prototype file; `overrides` replace parameter values (unknown names
// are an error). Throws fabatlas::InputError "file:line:col: message".
Prototype LoadPrototype(const std::filesystem::path& path, const std::map<std::string, double>& overrides = {});
Prototype ParsePrototype(const std::string& text, const std::string& file,
                         const std::map<std::string, double>& overrides = {});

}  // namespace fabatlas::prototype
