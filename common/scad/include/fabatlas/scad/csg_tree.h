// fabatlas/scad/csg_tree.h — OpenSCAD's evaluated CSG tree (`openscad -o
// model.csg`): every module call resolved to a node with literal arguments,
// e.g. `multmatrix([[1,0,0,2],...]) { cube(size = [56, 36, 15], center = false); }`.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace fabatlas::scad {

// An argument value: number, string, boolean, undef or a vector of values.
struct CsgValue {
  enum class Type { kUndef, kNumber, kString, kBoolean, kVector } type = Type::kUndef;
  double number = 0;
  std::string text;             // kString
  bool boolean = false;         // kBoolean
  std::vector<CsgValue> items;  // kVector
};

struct CsgNode {
  std::string name;                      // cube, multmatrix, group, text, ...
  std::map<std::string, CsgValue> args;  // named arguments
  std::vector<CsgValue> positional;      // unnamed arguments (rare in .csg)
  std::vector<CsgNode> children;
  int line = 0;  // 1-based line in the .csg text
  // The node in canonical OpenSCAD syntax (no whitespace, numbers in
  // shortest round-trip form): equal text means equal geometry, and it is a
  // valid OpenSCAD program on its own.
  std::string canonical;

  // A number argument, or `fallback` when absent or not a number.
  double Number(const std::string& key, double fallback) const;
  bool Boolean(const std::string& key, bool fallback) const;
};

// Parses a .csg file's text. The top-level statements become the children
// of one `group` node. Throws fabatlas::InputError naming `file` and the line
// for text that is not OpenSCAD CSG syntax.
CsgNode ParseCsg(const std::string& text, const std::string& file);

// What running OpenSCAD costs and answers.
struct OpenScadRun {
  std::string log_tail;  // OpenSCAD's last non-empty stderr line
  double seconds = 0;    // wall time of the process
};

// Runs `openscad -o OUT [-D name=literal ...] MODEL` (300 s limit) with the
// overrides already formatted as OpenSCAD literals. Returns false when
// OpenSCAD failed (exit status != 0 or no output), with run->log_tail saying
// why. Throws fabatlas::InputError when the program cannot be started or is
// not installed. Thread-safe (posix_spawn).
bool RunOpenScad(const std::filesystem::path& model, const std::filesystem::path& out,
                 const std::vector<std::pair<std::string, std::string>>& overrides, OpenScadRun* run);

}  // namespace fabatlas::scad
