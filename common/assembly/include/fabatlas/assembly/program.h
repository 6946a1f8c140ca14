// fabatlas/assembly/program.h — a FabHaL program (FabHacks, section 4.2) in YAML,
// with the semantics of the reference implementation (data/fabhacks/PARTS.md §2).
//
//   library: parts.yaml            # part library, relative to this file
//   start_with: {name: door, part: DoorRod, frame: [[0,0,500],[90,0,90]]}
//   parts: {hook1: HookEyeLeftS, basket: Basket}
//   end_with: {name: bottle, part: SoapBottle, primitive: rod, frame: [[0,0,253],[0,0,180]]}
//   steps:                          # in order
//     - {attach: hook1.ring, to: door.rod}                 # new part's primitive onto a placed one
//     - {attach: basket.rod1, to: hook1.hook, alignment: flip, is_fixed: false}
//     - {connect: hook2.hook, with: basket.rod2}           # closes a cycle
//
// Full reference: docs/assembly.md.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "fabatlas/assembly/part_library.h"

namespace fabatlas::assembly {

struct PartInstance {
  std::string name;  // instance name used in steps
  std::string part;  // key into the library
};

// One attach or connect. The relation is P_a·M_a(s_a)·A = P_b·M_b(s_b).
//   attach(new, placed): a = the placed primitive, b = the new part's
//     primitive, A from key "<placed>_<new>" with variant class names; the
//     new part's pose follows by forward kinematics (a spanning-tree edge).
//   connect(e1, e2): a = e1, b = e2, key "<e1>_<e2>" with base class names;
//     a loop-closing equality (PARTS.md §2.1).
struct Connection {
  int part_a = -1, part_b = -1;  // indices into Program::instances
  std::string primitive_a, primitive_b;
  bool closing = false;   // connect (closes a cycle) rather than attach
  bool flip = false;      // alignment: flip
  bool is_fixed = false;  // is_fixed_joint: both sides held under physics
  // Both sides held in the relaxation: is_fixed, or a clip connection (§1.10).
  bool held_in_relaxation = false;
  std::string key;  // alignment key, e.g. "Rod_HookFlex"
  Eigen::Matrix3d align = Eigen::Matrix3d::Identity();
  // Each side's connection parameters: ranges, kinds, starting values and
  // held (base-form) values (PARTS.md §2.3, spread as §1 says when several
  // connections share a primitive).
  std::vector<ParamSpec> params_a, params_b;
  int symmetry_axis_a = -1;  // closing only: free rotation of side a (§2.4)
  std::string where;         // "file:line:col" of the step
};

// The connections the reference gives a fixed base form on one side (PARTS.md
// §2.3): a part resting on another over an area — a surface on a surface, a
// roll (TubeCtl) on a tube or rod. Static friction holds them in the
// relaxation; SolveAssembly checks afterwards that they do not tip or slide.
bool IsRestingContact(const std::string& key);

struct Program {
  std::string file;
  PartLibrary library;
  std::vector<PartInstance> instances;  // [0] = environment (start_with)
  Frame environment_frame;
  int target = -1;  // end_with part instance
  // end_with names a primitive: its world frame P·B should be the target
  // frame; else (-1) the part frame, with the symmetry of the part's first
  // primitive (PARTS.md §2.1).
  int target_primitive = -1;
  Frame target_frame;
  bool target_match_rotation = true;    // end_with match_rotation (default true)
  std::vector<Connection> connections;  // in program order

  const Part& PartOf(int instance) const { return library.parts.at(instances[instance].part); }
  const Primitive& PrimitiveA(const Connection& c) const { return *PartOf(c.part_a).Find(c.primitive_a); }
  const Primitive& PrimitiveB(const Connection& c) const { return *PartOf(c.part_b).Find(c.primitive_b); }
  // The primitive whose class sets the target's symmetry.
  const Primitive& TargetPrimitive() const {
    return PartOf(target).primitives[target_primitive < 0 ? 0 : target_primitive];
  }
  // The target primitive's base frame in its part (identity for a part target).
  Eigen::Matrix4d TargetOffset() const;
};

// Parses a program. `mesh_dir` is where part meshes live (default: the
// FABATLAS_SHARED_DIR data/fabhacks/meshes when empty). Throws InputError
// "file:line:col: message" for syntax errors, unknown parts/primitives.
Program LoadProgram(const std::string& yaml_path, const std::string& mesh_dir = "");

// Same, from YAML text (for generated families); `name` is used in messages
// and `library_path` is the part library to use.
Program ParseProgram(const std::string& yaml_text, const std::string& name, const std::string& library_path,
                     const std::string& mesh_dir = "");

// The part library a program YAML names (`library:`, relative to the
// program file), as a path. Throws InputError("file:line:col: message").
std::string ProgramLibraryPath(const std::string& program_yaml);

// Default mesh directory: $FABATLAS_SHARED_DIR/data/fabhacks/meshes, else
// ../shared/data/fabhacks/meshes relative to the working directory.
// ($FABATLAS_SOURCE_DIR/../shared/... when only the source dir is known.)
std::string DefaultMeshDir();

}  // namespace fabatlas::assembly
