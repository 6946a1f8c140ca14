// One-line "file:line:col: message" errors for YAML inputs.
#pragma once

#include <string>

#include <yaml-cpp/yaml.h>

#include "fabatlas/error.h"
#include "fabatlas/yaml_place.h"

namespace fabatlas::assembly::internal {

[[noreturn]] inline void Fail(const std::string& file, const YAML::Node& n, const std::string& msg) {
  FailAt(YamlPlace(file, n.Mark()), msg);
}

inline YAML::Node LoadYamlFile(const std::string& file) {
  try {
    return YAML::LoadFile(file);
  } catch (const YAML::BadFile&) {
    throw InputError(file + ": cannot open file");
  } catch (const YAML::Exception& e) {
    FailAt(YamlPlace(file, e.mark), e.msg);
  }
}

inline double AsDouble(const std::string& file, const YAML::Node& n, const std::string& what) {
  try {
    return n.as<double>();
  } catch (const YAML::Exception&) {
    Fail(file, n, what + " must be a number");
  }
}

inline std::string AsString(const std::string& file, const YAML::Node& n, const std::string& what) {
  if (!n || !n.IsScalar()) Fail(file, n, what + " must be a string");
  return n.as<std::string>();
}

// Frame as [[x,y,z],[a,b,c]] or [x,y,z,a,b,c].
inline Frame AsFrame(const std::string& file, const YAML::Node& n, const std::string& what) {
  Frame f;
  if (n.IsSequence() && n.size() == 2 && n[0].IsSequence() && n[1].IsSequence() && n[0].size() == 3 &&
      n[1].size() == 3) {
    for (int i = 0; i < 3; ++i) {
      f.position[i] = AsDouble(file, n[0][i], what);
      f.euler_deg[i] = AsDouble(file, n[1][i], what);
    }
    return f;
  }
  if (n.IsSequence() && n.size() == 6) {
    for (int i = 0; i < 3; ++i) {
      f.position[i] = AsDouble(file, n[i], what);
      f.euler_deg[i] = AsDouble(file, n[i + 3], what);
    }
    return f;
  }
  Fail(file, n, what + " must be [[x,y,z],[a,b,c]] or [x,y,z,a,b,c]");
}

}  // namespace fabatlas::assembly::internal
