// Internal: what every operation node and check accepts (used by the linter
// in LoadDesign and by sample evaluation, so the two never disagree).
#pragma once

#include <map>
#include <string>
#include <vector>

namespace fabatlas::design {

// The shape an argument must have.
enum class ArgShape {
  kNumber,     // expression -> double
  kVec3,       // list of 3 expressions
  kVec2List,   // list of [x, y] pairs (>= 3 points)
  kVec3List,   // list of [x, y, z] triples
  kString,     // literal string (file names, options)
  kNumberMap,  // map name -> expression (OpenSCAD -D overrides)
  kChoiceMap,  // map name -> list of literal values an index selects (OpenSCAD enums)
};

struct ArgSpec {
  std::string name;
  ArgShape shape;
  bool required = true;
};

struct OpSchema {
  std::vector<ArgSpec> args;
  int min_children = 0;
  int max_children = 0;  // -1: unbounded
};

// Every operation node type, by name.
const std::map<std::string, OpSchema>& OperationSchemas();
// Every check type, by name.
const std::map<std::string, OpSchema>& CheckSchemas();
// Every property name.
const std::vector<std::string>& PropertyNames();

}  // namespace fabatlas::design
