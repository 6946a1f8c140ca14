// fabatlas/design/data_files.h — files a design needs that its node
// arguments do not name themselves, so that job bundles (protocol/
// job_bundle.h) carry them to workers that have nothing but the bundle.
#pragma once

#include <filesystem>
#include <vector>

#include "fabatlas/design/design.h"

namespace fabatlas::design {

struct DataFile {
  // Where evaluating the design looks for the file, relative to the design
  // file's directory.
  std::filesystem::path relative;
  // Where it is read from on this machine.
  std::filesystem::path source;
};

// The files `node` (not its children) needs beyond those its arguments name.
// For an `assembly` node: the part library a program names (when `file` is
// a program), and every part mesh of the library at `<meshes>/<name>`, where
// <meshes> is the node's `meshes:` directory or else `assembly_meshes`, read
// from where the node reads its meshes here (docs/design-format.md). For an
// `openscad` node: the files its model includes, uses and imports
// (scad/model_files.h), beside the model. Other operations need none. Throws InputError when a program or library file
// does not parse.
std::vector<DataFile> IndirectDataFiles(const Node& node, const std::filesystem::path& design_dir);

}  // namespace fabatlas::design
