// evaluate_model/source_files.h (internal to fabatlas_scad) — a model's .scad
// files parsed with their `include <...>` and `use <...>` statements as
// OpenSCAD 2021.01 reads them (OpenSCAD User Manual, "Include Statement" and
// "Libraries"):
//  - `include <f>` puts f's statements where it stands (its assignments,
//    definitions and instantiations); a file already being included (a
//    cycle; the model itself is not among them, so a model including itself
//    has its statements twice, as in OpenSCAD) or one not found is skipped
//    with a warning, as OpenSCAD does; files are named with links resolved;
//  - `use <f>`, anywhere in a file (or in a file it includes), makes f's own
//    top-level modules and functions visible in the whole file; the file is
//    read when a name is first looked up in it (evaluator.h), so cycles of
//    uses are harmless;
//  - a name is looked up beside the file that names it, then in each
//    directory of OPENSCADPATH, then in OpenSCAD's user library directory
//    (~/.local/share/OpenSCAD/libraries) and Debian's installed one
//    (/usr/share/openscad/libraries); an absolute name as it is. Confinement
//    of a job's files is model_files.h's, checked before any evaluation.
// Every included or used file is parsed once per process (cached by its
// absolute path, size and modification time; thread-safe); the model itself
// is parsed per call.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "syntax.h"

namespace fabatlas::scad::internal {

struct SourceFile {
  std::string path;                 // as messages name it
  std::vector<StmtPtr> statements;  // included files' statements in place
  std::vector<std::string> uses;    // the files it uses, found, each once, in the order named
  // Its own top-level definitions (a later one of a name wins, as in OpenSCAD):
  // what a file that uses it sees.
  std::map<std::string, std::shared_ptr<const ModuleDef>> modules;
  std::map<std::string, std::shared_ptr<const FunctionDef>> functions;
  // "FILE:LINE: include <x>: ..." for each file skipped (not found, a cycle).
  std::vector<std::string> warnings;
};

// The model's text, named `file` (whose directory the names it includes and
// uses are found from), parsed. Throws NotNative (its `file` set when the
// place is in an included file).
std::shared_ptr<const SourceFile> ParseModel(const std::string& text, const std::string& file);

// The used file at `path` (as SourceFile::uses holds it), parsed once per
// process. Throws NotNative naming that file when it cannot be read or parsed.
std::shared_ptr<const SourceFile> UsedFile(const std::string& path);

// Where OpenSCAD finds `name` named by a file in directory `dir`, or empty
// when nowhere (a missing file or a directory).
std::filesystem::path FindSourceFile(const std::filesystem::path& dir, const std::string& name);

}  // namespace fabatlas::scad::internal
