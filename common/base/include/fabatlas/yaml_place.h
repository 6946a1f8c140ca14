// fabatlas/yaml_place.h — the SourcePlace of a node or error in a YAML file
// (yaml-cpp's YAML::Mark counts lines and columns from 0; messages count from
// 1). Used by every YAML loader: designs, jobs, prototypes, assembly
// programs. Header-only: only code that already reads YAML includes it.
#pragma once

#include <string>

#include <yaml-cpp/mark.h>

#include "fabatlas/source_place.h"

namespace fabatlas {

// The place of `mark` in `file`; a null mark (a node not read from the file,
// such as a missing key's) names the file alone.
inline SourcePlace YamlPlace(const std::string& file, const YAML::Mark& mark) {
  if (mark.is_null()) return {file, 0, 0};
  return {file, mark.line + 1, mark.column + 1};
}

}  // namespace fabatlas
