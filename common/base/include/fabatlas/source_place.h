// fabatlas/source_place.h — a place in a file the user wrote (a design, job,
// prototype or assembly file), as input errors name it (fabatlas/error.h):
//   "configs/designs/vase.yaml:12:7: unknown node type 'sphear'"
// The one way every loader writes "file:line:column: message"; for a place in
// a YAML file see fabatlas/yaml_place.h.
#pragma once

#include <string>

namespace fabatlas {

struct SourcePlace {
  std::string file;  // as the user typed it
  int line = 0;      // 1-based; 0 = unknown
  int column = 0;    // 1-based
  // "file:line:column", or just "file" when the line is unknown.
  std::string str() const;
};

// Throws InputError("<place.str()>: <what>").
[[noreturn]] void FailAt(const SourcePlace& place, const std::string& what);

}  // namespace fabatlas
