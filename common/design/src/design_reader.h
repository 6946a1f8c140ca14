// Reading a design file's YAML with places for its errors, shared by the
// parts of the reader (load_design.cc: parameters, constraints, checks,
// properties; read_design_tree.cc: the tree and a reconfigurable's objects,
// states and transitions). Internal.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cctype>
#include <filesystem>
#include <map>
#include <set>
#include <string>

#include "expression.h"
#include "fabatlas/design/design.h"
#include "fabatlas/error.h"
#include "fabatlas/yaml_place.h"
#include "node_schema.h"

namespace fabatlas::design {

// The YAML of one design file: values read with the file, line and column
// of each in its errors (InputError, one line).
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  SourcePlace At(const YAML::Node& n) const { return YamlPlace(file_, n.Mark()); }

  [[noreturn]] void Fail(const YAML::Node& n, const std::string& what) const { FailAt(At(n), what); }
  [[noreturn]] void Fail(const SourcePlace& p, const std::string& what) const { FailAt(p, what); }

  std::string String(const YAML::Node& n, const std::string& what) const {
    if (!n.IsScalar()) Fail(n, what + " must be a single value");
    return n.Scalar();
  }

  // A finite number written literally (ranges, defaults, voxel size).
  double Number(const YAML::Node& n, const std::string& what) const {
    if (!n.IsScalar()) Fail(n, what + " must be a number");
    const std::string& s = n.Scalar();
    double v = 0;
    std::size_t used = 0;
    try {
      v = std::stod(s, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    std::string lower = s;
    for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (lower == ".nan" || lower == "nan") Fail(n, what + " is NaN");
    if (lower == ".inf" || lower == "-.inf" || lower == "+.inf") Fail(n, what + " is infinite");
    if (used == 0 || used != s.size()) Fail(n, what + " must be a number, got '" + s + "'");
    if (!std::isfinite(v)) Fail(n, what + " is not finite");
    return v;
  }

  void OnlyKeys(const YAML::Node& map, const std::set<std::string>& allowed, const std::string& what) const {
    for (auto it = map.begin(); it != map.end(); ++it) {
      std::string key = it->first.Scalar();
      if (!allowed.count(key)) {
        std::string list;
        for (const auto& k : allowed) list += (list.empty() ? "" : ", ") + k;
        Fail(it->first, "unknown key '" + key + "' in " + what + " (expected one of: " + list + ")");
      }
    }
  }

  Argument ToArgument(const YAML::Node& n) const {
    Argument a;
    a.place = At(n);
    if (n.IsScalar()) {
      a.kind = Argument::Kind::kScalar;
      a.text = n.Scalar();
      a.quoted = n.Tag() == "!";  // yaml-cpp tags quoted scalars "!", plain ones "?"
    } else if (n.IsSequence()) {
      a.kind = Argument::Kind::kList;
      for (const auto& item : n) a.items.push_back(ToArgument(item));
    } else if (n.IsMap()) {
      a.kind = Argument::Kind::kMap;
      for (auto it = n.begin(); it != n.end(); ++it) {
        a.keys.push_back(it->first.Scalar());
        a.items.push_back(ToArgument(it->second));
      }
    } else {
      Fail(n, "empty value");
    }
    return a;
  }

 private:
  std::string file_;
};

// read_design_tree.cc: the arguments of a node or check against its schema:
// required ones present, no unknown ones, each argument linted (its shape and
// every expression compiled against the design's names).
void LintArgs(const std::map<std::string, Argument>& args, const OpSchema& schema, const SourcePlace& place,
              const std::string& what, Scope& scope, const std::filesystem::path& dir);

// read_design_tree.cc: the geometry tree under `y`, linted against its
// node schemas (node_schema.h) and the design's names; `depth` bounds nesting.
Node ReadNode(const Reader& r, const YAML::Node& y, Scope& scope, const std::filesystem::path& dir, int depth);

// read_design_tree.cc: the objects, states and transitions of a
// reconfigurable (Reconfigurables), when the design has them.
void ReadReconfigurable(const Reader& r, const YAML::Node& root, Design& d, Scope& scope,
                        const std::filesystem::path& dir);

// read_design_tree.cc: every `object` and `carve_swept` node names a
// declared object and transition, and no object contains itself.
void LintReferences(const Design& d);

}  // namespace fabatlas::design
