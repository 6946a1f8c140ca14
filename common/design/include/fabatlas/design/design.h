// fabatlas/design/design.h — the parametric design model (Fab Forms, Sec. 4).
//
// A design F is: exposed parameters U (what end users move), mutable low-level
// parameters (solved for), constraints C_F linking them, a tree of operation
// nodes whose parameters are expressions over both, validity checks W_F and
// properties P_F. The YAML form is documented in docs/design-format.md.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fabatlas/source_place.h"

namespace fabatlas::design {

// Where something was written: "file:line:col" for messages.
using ::fabatlas::SourcePlace;

enum class ParameterKind { kReal, kInteger, kEnumerated };

// An exposed parameter u_i. Enumerated values are addressed by index 0..k-1
// inside expressions; `labels` are what users see.
struct ExposedParameter {
  std::string name;
  ParameterKind kind = ParameterKind::kReal;
  double min = 0, max = 1;          // for enumerated: 0 .. labels.size()-1
  double default_value = 0;         // the design's, else the middle of the range
  std::vector<std::string> labels;  // enumerated only
  std::string description;          // optional: shown to users (the customiser)
  std::string group;                // optional: the customiser groups parameters by it
  SourcePlace place;
};

// A parameter of the design's model that stays at one value (e.g. an
// OpenSCAD Customizer parameter `import-scad` did not expose): shown to users
// read-only so they see the whole model; never passed to the tree.
struct FixedParameter {
  std::string name;
  std::string value;        // as the model writes it (an OpenSCAD literal)
  std::string description;  // optional, as for exposed parameters
  std::string group;        // optional
  std::string why;          // optional: why it is not exposed, in words
  SourcePlace place;
};

// A named point of the exposed space the designer offers (e.g. an OpenSCAD
// parameter set); parameters it does not name take their defaults.
struct Preset {
  std::string name;
  std::map<std::string, double> values;  // every exposed parameter (enums by index)
  SourcePlace place;
};

// A mutable low-level parameter: solved for, with bounds and a default the
// solver stays as close to as the constraints allow.
struct MutableParameter {
  std::string name;
  double min = -1e9, max = 1e9;
  double default_value = 0;
  SourcePlace place;
};

enum class Relation { kEqual, kLessEqual, kGreaterEqual };

// lhs (relation) rhs, both muparser expressions over parameter names.
struct Constraint {
  std::string text;  // as written
  std::string lhs, rhs;
  Relation relation = Relation::kEqual;
  SourcePlace place;
};

// A node argument: an expression (numbers are expressions), a list, or a map
// of name -> argument (OpenSCAD overrides). Kept as written; resolved per
// sample. Which arguments are expressions and which are strings (file names,
// options) is fixed by the operation's schema.
struct Argument {
  enum class Kind { kScalar, kList, kMap } kind = Kind::kScalar;
  std::string text;               // scalar: expression or string
  bool quoted = false;            // scalar written in quotes (a string, never a number)
  std::vector<Argument> items;    // list items, or map values
  std::vector<std::string> keys;  // map keys, parallel to items
  SourcePlace place;
};

struct Node {
  std::string op;                        // e.g. "sphere", "difference"
  std::string name;                      // optional, for reports
  std::map<std::string, Argument> args;  // op arguments
  std::vector<Node> children;
  SourcePlace place;
};

// A validity check w_i. type is one of: watertight, min_thickness, stands, fem.
// Constraint satisfiability and geometry generation are always checked first.
struct CheckSpec {
  std::string type;
  std::string name;  // defaults to type
  std::map<std::string, Argument> args;
  SourcePlace place;
};

// Reconfigurables (the paper, Sec. 3): named objects moved by keyframed
// rigid motions along the transitions of a state graph.
//
// An object is a tree modelled in its pose in the first state (its body
// frame). A motion maps body to world coordinates for t in [0, 1]:
//   f(t) x = R(t) (x - pivot) + pivot + T(t)
// with T a cubic Bezier curve (4 control points; 2 points = a straight line
// at constant speed) and R the slerp between rotation keys evenly spaced in t
// (each key [axis_x, axis_y, axis_z, degrees], absolute rotations). Every
// number is an expression; they are resolved per sample.
struct ObjectMotion {
  std::string object;
  Argument translation;  // list of 2 or 4 [x, y, z]; empty list = none
  Argument rotation;     // list of [ax, ay, az, deg]; empty list = none
  Argument pivot;        // [x, y, z]; empty = origin
  bool has_translation = false, has_rotation = false, has_pivot = false;
  SourcePlace place;
};

// An edge of the state graph. Objects without a motion stay where they are
// in `from` (the pose the transitions leading there left them in).
struct Transition {
  std::string name;  // defaults to "from->to"
  std::string from, to;
  std::vector<ObjectMotion> motions;
  SourcePlace place;
};

struct DesignObject {
  std::string name;
  Node tree;
  SourcePlace place;
};

struct Design {
  std::filesystem::path file;  // where it was loaded from
  std::string name;
  double voxel_size = 0.5;  // mm
  std::vector<ExposedParameter> exposed;
  std::vector<MutableParameter> mutables;
  std::vector<Constraint> constraints;
  Node tree;
  std::vector<CheckSpec> checks;
  std::vector<std::string> properties;  // volume, area, bbox
  std::vector<Preset> presets;          // optional, in file order
  std::vector<FixedParameter> fixed;    // optional, in file order (shown, not sampled)
  // Reconfigurables (optional; see ObjectMotion). Transitions are listed so
  // that each one's `from` state is the first state or the `to` of an earlier
  // transition (the state poses are propagated in that order).
  std::vector<DesignObject> objects;
  std::vector<std::string> states;
  std::vector<Transition> transitions;
  std::string canonical_text;  // the file's bytes, for hashing

  const ExposedParameter* FindExposed(const std::string& name) const;
  const DesignObject* FindObject(const std::string& name) const;
  const Transition* FindTransition(const std::string& name) const;
};

// Reads and lints a design file. Throws fabatlas::InputError with a one-line
// "file:line:col: message" on any problem: malformed YAML, unknown keys or node
// types, unknown names in expressions, NaN, min > max, defaults out of range,
// missing mesh files.
Design LoadDesign(const std::filesystem::path& path);

// The same from text already in memory; `file` names it in messages and
// anchors relative mesh paths.
Design ParseDesign(const std::string& text, const std::filesystem::path& file);

// A point u in the exposed space, by parameter name.
using Point = std::map<std::string, double>;

// Parses "name=value,name=value" (enumerated values by label or index) and
// fills every parameter not given with its default. Throws InputError naming
// `what` (e.g. "--at") for unknown names, NaN and out-of-range values.
Point ParsePoint(const Design& design, const std::string& text, const std::string& what);

// The default point: every exposed parameter at its default.
Point DefaultPoint(const Design& design);

}  // namespace fabatlas::design
