// Internal: the operation nodes of a design tree, applied to resolved values.
#pragma once

#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "fabatlas/design/design.h"
#include "fabatlas/error.h"
#include "fabatlas/geometry/solid.h"

namespace fabatlas::design {

// A sample-level failure raised while evaluating (not a design error).
class SampleFailure : public std::runtime_error {
 public:
  SampleFailure(std::string type, const std::string& reason) : std::runtime_error(reason), type_(std::move(type)) {}
  const std::string& type() const { return type_; }

 private:
  std::string type_;
};

// A problem of the design itself met during evaluation (an unreadable mesh
// file, a missing program): reported to the user, never a sample outcome.
class DesignFault : public InputError {
 public:
  using InputError::InputError;
};

// A node's arguments with every expression evaluated at the current sample.
struct ResolvedArgs {
  struct Value {
    std::vector<double> numbers;        // scalars, vectors, flattened point lists
    std::vector<std::string> keys;      // map keys (OpenSCAD overrides)
    std::vector<std::string> literals;  // `set` of openscad: each key's value as an OpenSCAD literal
    std::string text;                   // strings
    std::string digest;                 // file contents digest, for keys
    SourcePlace place;
  };
  std::map<std::string, Value> values;

  double Number(const std::string& name, double fallback = 0) const;
  geometry::Vec3 Vec3(const std::string& name) const;
  std::string Text(const std::string& name, const std::string& fallback = "") const;
  // Canonical text of every resolved value: the ρ of Fab Forms Sec. 6.
  std::string Canonical() const;
};

// Computes one node from its resolved arguments and its children's solids.
// Meshes read from outside fabatlas (mesh, openscad) are appended to
// `outside` when given (struct OutsideMesh, openscad_node.h).
struct OutsideMesh;
geometry::Solid ApplyOperation(const Node& node, const ResolvedArgs& args, std::vector<geometry::Solid>& children,
                               const geometry::GridSpec& grid, const std::filesystem::path& design_dir,
                               std::vector<OutsideMesh>* outside = nullptr);

}  // namespace fabatlas::design
