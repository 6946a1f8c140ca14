// fabatlas/scad/model_files.h — the files an OpenSCAD model reads besides
// itself: `include <...>` and `use <...>` (recursively), and the literal file
// names of `import(...)` and `surface(...)`, found where OpenSCAD looks for
// them (OpenSCAD User Manual, "Include Statement" and "Libraries"): beside
// the file that names them, then in each directory of OPENSCADPATH. Job
// bundles and on-the-fly imports carry them so the model evaluates the same
// anywhere (docs/openscad.md).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace fabatlas::scad {

struct ModelFile {
  // Where OpenSCAD finds it when the model is read from a directory D holding
  // it at D/relative (beside the file that names it, so found first).
  std::filesystem::path relative;
  // Where it is read from on this machine.
  std::filesystem::path source;
};

// The files `model` needs, each once, in the order first named. Names that
// are not found (OpenSCAD's own library directory) are left out: OpenSCAD
// reports a missing file itself when it evaluates the model.
// `openscadpath` is the OPENSCADPATH value (directories separated by ':').
//
// Confinement: a job bundle carries only the files inside the model's
// directory, and those are all an evaluation may read. A literal name that
// is absolute (`import("/etc/x.stl")`), that leaves the model's directory
// (`use <../lib.scad>`), or a found file that is a link resolving outside
// the directory it was found in (the model's, or the OPENSCADPATH directory
// of a library) throws fabatlas::InputError, one line:
//   "<file>:<line>: use <../lib.scad> leaves the model's directory; ..."
// before anything reads that file. Computed names (`import(str(a, b))`) are
// not seen here (docs/operations.md, Bundle confinement).
// Throws fabatlas::InputError naming the file when a .scad file cannot be read.
std::vector<ModelFile> ModelFiles(const std::filesystem::path& model, const std::string& openscadpath);

// ModelFiles with this process's OPENSCADPATH.
std::vector<ModelFile> ModelFiles(const std::filesystem::path& model);

}  // namespace fabatlas::scad
