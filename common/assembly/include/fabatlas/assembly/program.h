// fabatlas/assembly/program.h — a FabHaL program (FabHacks, section 4.2) in YAML.
//
//   library: parts.yaml            # part library, relative to this file
//   start_with: {name: door, part: DoorRod, frame: [[0,0,500],[90,0,90]]}
//   end_with:   {name: bottle, part: SoapBottle, frame: [[0,0,253],[0,0,180]]}
//   parts: {hook1: HookEyeLeftS, basket: Basket}
//   connect:
//     - {a: hook1.ring, b: door.rod, alignment: flip, is_fixed: false}
//
// Full reference: docs/assembly.md.
#pragma once

#include <string>
#include <vector>

#include "fabatlas/assembly/part_library.h"

namespace fabatlas::assembly {

struct PartInstance {
  std::string name;  // instance name used in connect
  std::string part;  // key into the library
};

struct Connection {
  int part_a = -1, part_b = -1;  // indices into Program::instances
  std::string primitive_a, primitive_b;
  bool flip = false;      // alignment: flip
  bool is_fixed = false;  // DoFs held constant (friction / tape)
  std::vector<double> fixed_a, fixed_b;  // optional fixed parameter values
  std::string where;      // "file:line:col" of the connect entry
};

struct Program {
  std::string file;
  PartLibrary library;
  std::vector<PartInstance> instances;  // [0] = environment (start_with)
  Frame environment_frame;
  int target = -1;                      // end_with part instance
  Frame target_frame;
  bool target_match_rotation = true;  // end_with match_rotation (default true)
  std::vector<Connection> connections;

  const Part& PartOf(int instance) const { return library.parts.at(instances[instance].part); }
  const Primitive& PrimitiveA(const Connection& c) const { return *PartOf(c.part_a).Find(c.primitive_a); }
  const Primitive& PrimitiveB(const Connection& c) const { return *PartOf(c.part_b).Find(c.primitive_b); }
};

// Parses a program. `mesh_dir` is where part meshes live (default: the
// FABATLAS_SHARED_DIR data/fabhacks/meshes when empty). Throws InputError
// "file:line:col: message" for syntax errors, unknown parts/primitives.
Program LoadProgram(const std::string& yaml_path, const std::string& mesh_dir = "");

// Same, from YAML text (for generated families); `name` is used in messages
// and `library_path` is the part library to use.
Program ParseProgram(const std::string& yaml_text, const std::string& name,
                     const std::string& library_path, const std::string& mesh_dir = "");

// The part library a program YAML names (`library:`, relative to the
// program file), as a path. Throws InputError("file:line:col: message").
std::string ProgramLibraryPath(const std::string& program_yaml);

// Default mesh directory: $FABATLAS_SHARED_DIR/data/fabhacks/meshes, else
// ../shared/data/fabhacks/meshes relative to the working directory.
// ($FABATLAS_SOURCE_DIR/../shared/... when only the source dir is known.)
std::string DefaultMeshDir();

}  // namespace fabatlas::assembly
